// What a trajectory constraint follows (§4): a point path n(t) known through n, ṅ and n̈ at
// the current time only. Splines, preroll segments and goal behaviours implement it elsewhere
// (wobble/control); the constraint never needs to know their form.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <utility>

namespace wobble {

struct PathSample {
  Eigen::VectorXd n, n_dot, n_ddot;  // each of the path's dimension
};

class PointPath {
 public:
  virtual ~PointPath() = default;
  // Dimension of the points (2 or 3).
  virtual int dim() const = 0;
  // n(t), ṅ(t), n̈(t). Called once per step at the step's start time (and by impulses).
  virtual PathSample Evaluate(double t) const = 0;
};

// A path from a function (tests, quick scripts, behaviours that rebuild their curve).
class FunctionPath : public PointPath {
 public:
  FunctionPath(int dim, std::function<PathSample(double)> f) : dim_(dim), f_(std::move(f)) {}
  int dim() const override { return dim_; }
  PathSample Evaluate(double t) const override { return f_(t); }

 private:
  int dim_;
  std::function<PathSample(double)> f_;
};

// A point that does not move (what a nail holds; also handy as a path).
class FixedPath : public PointPath {
 public:
  explicit FixedPath(Eigen::VectorXd where) : where_(std::move(where)) {}
  int dim() const override { return int(where_.size()); }
  PathSample Evaluate(double) const override {
    return {where_, Eigen::VectorXd::Zero(where_.size()), Eigen::VectorXd::Zero(where_.size())};
  }

 private:
  Eigen::VectorXd where_;
};

}  // namespace wobble
