// Paths for trajectory control (Witkin & Welch 1990, §4, §4.1): a controlled point follows
// n(t), and the constraint R p − n(t) = 0 needs n, ṅ and n̈ at the current time only
// ("we need not know anything further about the form of n"). Everything here works in any
// dimension (2D and 3D bodies), positions being Eigen::VectorXd of that size.
//
//   HermiteSegment   the cubic from (t0, x0, v0) to (t1, x1, v1): constraint preroll (§4.1) and
//                    the Chase behaviour (§4.2) are both made of it
//   KeyframeSpline   the piecewise cubic through keyframed positions (§4.1), C² at the keys,
//                    natural or with given end velocities
//   PrerolledPath    a preroll segment from the point's state when control is switched on to
//                    the path's position and velocity at its onset, then the path itself
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "wobble/world/point_path.h"

namespace wobble::control {

// The constraints' path interface: n, ṅ, n̈ at one time (PathSample: n, n_dot, n_ddot).
using Path = PointPath;
using PathPoint = PathSample;

// x(t) = x0 + v0 τ + c τ² + d τ³, τ = t − t0, with x(t0) = x0, ẋ(t0) = v0, x(t1) = x1,
// ẋ(t1) = v1. Outside [t0, t1] the point moves on at the end's velocity (a straight line,
// zero acceleration), so the path is C¹ everywhere.
class HermiteSegment : public Path {
 public:
  // t1 > t0 and all vectors of one size (asserted).
  HermiteSegment(double t0, Eigen::VectorXd x0, Eigen::VectorXd v0, double t1, Eigen::VectorXd x1,
                 Eigen::VectorXd v1);
  int dim() const override { return int(x0_.size()); }
  PathPoint Evaluate(double t) const override;
  double t0() const { return t0_; }
  double t1() const { return t1_; }

 private:
  double t0_, t1_;
  Eigen::VectorXd x0_, v0_, x1_, v1_, c_, d_;
};

// The default final velocity of a segment whose end velocity was not given (Chase without a
// velocity, §4.2: "a default based on the current position and velocity, duration and distance
// to the target"): v1 = 2 (x1 − x0)/T − v0, the end velocity of the constant-acceleration
// motion from (x0, v0) to x1 in time T, so the cubic is that parabola (its τ³ term is zero).
Eigen::VectorXd DefaultFinalVelocity(const Eigen::VectorXd& x0, const Eigen::VectorXd& v0, const Eigen::VectorXd& x1,
                                     double duration);

// Keyframed control-point positions (§4.1): piecewise cubic through (t_i, x_i), i = 0..n−1,
// n >= 2, twice continuously differentiable at the inner keys. End conditions: a given velocity
// at an end ("clamped"), or zero acceleration there ("natural") when none is given. Before the
// first key and after the last one the point moves on in a straight line at the end velocity.
class KeyframeSpline : public Path {
 public:
  struct Options {
    std::optional<Eigen::VectorXd> start_velocity, end_velocity;
  };
  // Builds the spline; an empty string on success, otherwise what is wrong with the keys
  // (fewer than two, times not strictly increasing or not finite, positions of mixed sizes).
  static std::string Validate(const std::vector<double>& times, const std::vector<Eigen::VectorXd>& positions,
                              const Options& options);
  // Keys must pass Validate (asserted).
  KeyframeSpline(std::vector<double> times, std::vector<Eigen::VectorXd> positions, Options options);
  KeyframeSpline(std::vector<double> times, std::vector<Eigen::VectorXd> positions)
      : KeyframeSpline(std::move(times), std::move(positions), Options{}) {}
  int dim() const override { return int(positions_[0].size()); }
  PathPoint Evaluate(double t) const override;
  double start_time() const { return times_.front(); }
  double end_time() const { return times_.back(); }
  const std::vector<double>& times() const { return times_; }
  // The velocities at the keys (the spline's slopes).
  const std::vector<Eigen::VectorXd>& key_velocities() const { return slopes_; }

 private:
  std::vector<double> times_;
  std::vector<Eigen::VectorXd> positions_, slopes_;
  std::vector<HermiteSegment> segments_;
};

// Constraint preroll (§4.1): from `start_time` until `path_start` the point follows the cubic
// that joins its current position and velocity to the path's position and velocity at
// `path_start`; from then on the path itself. path_start > start_time (asserted).
class PrerolledPath : public Path {
 public:
  PrerolledPath(std::shared_ptr<const Path> path, double start_time, const Eigen::VectorXd& position,
                const Eigen::VectorXd& velocity, double path_start);
  int dim() const override { return path_->dim(); }
  PathPoint Evaluate(double t) const override;
  const HermiteSegment& preroll() const { return preroll_; }
  double path_start() const { return path_start_; }

 private:
  std::shared_ptr<const Path> path_;
  HermiteSegment preroll_;
  double path_start_;
};

}  // namespace wobble::control
