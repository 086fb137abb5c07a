// The viewer's mouse pulls as World controllers, added by the caller (World::AddController)
// and undone by Release; the cursor moves between steps (Aim).
//   SpringPull      an FFD body's point on a damped spring to the cursor (the springs of
//                   Fig. 4.4 in the thesis, one that moves). The anchor is a parameter of the
//                   force law, read inside the step, so Aim moves it at once.
//   ConstraintPull  a material point of any body led to the cursor by a trajectory
//                   constraint (Witkin & Welch §4) along an ApproachPath. The path is re-aimed
//                   at the start of the next step (BeforeStep), from where it is then with its
//                   velocity, so the constraint stays satisfied whenever the cursor moves.
#pragma once

#include <Eigen/Core>
#include <memory>

#include "wobble/dynamics/forces.h"
#include "wobble/world/controller.h"
#include "wobble/world/point_path.h"
#include "wobble/world/world.h"

namespace wobble::control {

// A critically damped approach to the target c with time constant tau that starts at the
// position n0 and velocity v0 at time t0 (so a trajectory constraint holds when it is added
// or re-aimed, and no impulse is needed):
//   n(s) = c + (A + B s) e^(-s/tau),  A = n0 - c,  B = v0 + A/tau,  s = t - t0.
class ApproachPath : public PointPath {
 public:
  ApproachPath(double t0, Eigen::VectorXd n0, const Eigen::VectorXd& v0, Eigen::VectorXd target, double tau);
  int dim() const override { return int(c_.size()); }
  PathSample Evaluate(double t) const override;
  const Eigen::VectorXd& target() const { return c_; }

 private:
  double t0_;
  Eigen::VectorXd c_, a_, b_;
  double tau_;
};

class SpringPull : public Controller {
 public:
  // Adds `spring` (body, lattice point, anchor, stiffness, damping) to the world's springs.
  SpringPull(World& world, const Spring& spring);
  // The new anchor, in the body's dimension.
  void Aim(World& world, const Eigen::VectorXd& anchor);
  // Removes the spring (call once, before removing the controller).
  void Release(World& world);
  // In three coordinates (Spring's layout: a 2D body's z is 0).
  const Eigen::Vector3d& lattice_coords() const { return lattice_coords_; }
  const Eigen::Vector3d& anchor() const { return anchor_; }

 private:
  size_t index_;  // in the world's springs
  Eigen::Vector3d lattice_coords_, anchor_;
};

class ConstraintPull : public Controller {
 public:
  // Adds a trajectory constraint that holds `point` where it is, moving as it moves now.
  ConstraintPull(World& world, const MaterialPoint& point, double time_constant);
  void Aim(const Eigen::VectorXd& target) { aim_ = target; }
  void BeforeStep(World& world) override;  // re-aims the path at the aim, from where it is now
  void Release(World& world);              // removes the constraint
  const MaterialPoint& point() const { return point_; }
  const Eigen::VectorXd& target() const { return path_->target(); }
  const Eigen::VectorXd& aim() const { return aim_; }
  int constraint() const { return id_; }  // −1 once released

 private:
  MaterialPoint point_;
  double tau_;
  std::shared_ptr<const ApproachPath> path_;
  Eigen::VectorXd aim_;
  int id_ = -1;
};

}  // namespace wobble::control
