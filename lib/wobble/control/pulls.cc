#include "wobble/control/pulls.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace wobble::control {

ApproachPath::ApproachPath(double t0, Eigen::VectorXd n0, const Eigen::VectorXd& v0, Eigen::VectorXd target, double tau)
    : t0_(t0), c_(std::move(target)), a_(n0 - c_), b_(v0 + a_ / tau), tau_(tau) {
  if (!(tau > 0)) throw std::invalid_argument("ApproachPath: the time constant must be positive");
}

PathSample ApproachPath::Evaluate(double t) const {
  const double s = std::max(0.0, t - t0_), e = std::exp(-s / tau_);
  const Eigen::VectorXd ab = a_ + b_ * s;
  PathSample p;
  p.n = c_ + ab * e;
  p.n_dot = (b_ - ab / tau_) * e;
  p.n_ddot = (-2.0 * b_ / tau_ + ab / (tau_ * tau_)) * e;
  return p;
}

SpringPull::SpringPull(World& world, const Spring& spring)
    : lattice_coords_(spring.lattice_coords), anchor_(spring.anchor) {
  index_ = size_t(world.AddSpring(spring));
}

void SpringPull::Aim(World& world, const Eigen::VectorXd& anchor) {
  if (anchor.size() < 2 || anchor.size() > 3) throw std::invalid_argument("SpringPull::Aim: an anchor has 2 or 3 coordinates");
  anchor_.setZero();
  anchor_.head(anchor.size()) = anchor;
  world.mutable_options().params.springs.at(index_).anchor = anchor_;
}

void SpringPull::Release(World& world) {
  auto& springs = world.mutable_options().params.springs;
  if (index_ < springs.size()) springs.erase(springs.begin() + long(index_));
  index_ = size_t(-1);
}

ConstraintPull::ConstraintPull(World& world, const MaterialPoint& point, double time_constant)
    : point_(point), tau_(time_constant) {
  const Eigen::VectorXd at = world.PointPosition(point);
  path_ = std::make_shared<ApproachPath>(world.time(), at, world.PointVelocity(point), at, tau_);
  aim_ = at;
  id_ = world.AddTrajectory(point, path_);
}

void ConstraintPull::BeforeStep(World& world) {
  if (id_ < 0 || aim_ == path_->target()) return;
  // re-aimed from where the path is now, with its velocity: the constraint stays satisfied
  const PathSample s = path_->Evaluate(world.time());
  path_ = std::make_shared<ApproachPath>(world.time(), s.n, s.n_dot, aim_, tau_);
  world.SetPath(id_, path_);
}

void ConstraintPull::Release(World& world) {
  if (id_ >= 0 && world.exists(id_)) world.Remove(id_);
  id_ = -1;
}

}  // namespace wobble::control
