// Newton's method for the implicit integrators (implicit Euler, variational).
#pragma once

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "wobble/core/types.h"
#include "wobble/dynamics/status.h"

namespace wobble {

// Newton's method with a forward-difference Jacobian and backtracking on |r|, for the implicit
// integrators. x holds the initial guess and receives the solution.
template <class T, class Residual, class Vec> StepStatus SolveNewton(Residual&& residual, Vec* x) {
  const int n = int(x->size());
  auto norm = [](const Vec& r) {
    double m = 0.0;
    for (int i = 0; i < r.size(); ++i) m = std::max(m, std::abs(double(ScalarValue(r[i]))));
    return m;
  };
  using Jacobian = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, Vec::MaxRowsAtCompileTime, Vec::MaxRowsAtCompileTime>;
  Vec r, r_probe, trial;
  StepStatus st;
  if (!(st = residual(*x, &r)).ok()) return st;
  const double scale = 1.0 + norm(r);
  for (int iter = 0; iter < 30; ++iter) {
    const double r_norm = norm(r);
    if (r_norm <= 1e-12 * scale) return {};
    Jacobian jac(n, n);
    for (int i = 0; i < n; ++i) {
      const double eps = 1e-7 * std::max(1.0, std::abs(double(ScalarValue((*x)[i]))));
      Vec xp = *x;
      xp[i] += T(eps);
      if (!(st = residual(xp, &r_probe)).ok()) return st;
      jac.col(i) = (r_probe - r) / T(eps);
    }
    const Vec dx = jac.partialPivLu().solve(r);
    // backtrack until the residual decreases (contact forces are only piecewise smooth)
    double step = 1.0;
    for (int k = 0; k < 12; ++k, step *= 0.5) {
      trial = *x - T(step) * dx;
      if (!(st = residual(trial, &r_probe)).ok()) return st;
      if (norm(r_probe) < r_norm) break;
    }
    const double dx_norm = step * norm(dx);
    *x = trial;
    r = r_probe;
    if (dx_norm <= 1e-13 * (1.0 + norm(*x))) return {};
  }
  return norm(r) <= 1e-8 * scale ? StepStatus{} : StepStatus{StepStatus::Code::kSolverFailed, norm(r)};
}

}  // namespace wobble
