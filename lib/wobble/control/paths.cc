#include "wobble/control/paths.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace wobble::control {

HermiteSegment::HermiteSegment(double t0, Eigen::VectorXd x0, Eigen::VectorXd v0, double t1, Eigen::VectorXd x1,
                               Eigen::VectorXd v1)
    : t0_(t0), t1_(t1), x0_(std::move(x0)), v0_(std::move(v0)), x1_(std::move(x1)), v1_(std::move(v1)) {
  assert(t1_ > t0_);
  assert(v0_.size() == x0_.size() && x1_.size() == x0_.size() && v1_.size() == x0_.size());
  // x(τ) = x0 + v0 τ + c τ² + d τ³ with x(h) = x1, ẋ(h) = v1
  const double h = t1_ - t0_;
  c_ = (3.0 * (x1_ - x0_) / h - 2.0 * v0_ - v1_) / h;
  d_ = (2.0 * (x0_ - x1_) / h + v0_ + v1_) / (h * h);
}

PathPoint HermiteSegment::Evaluate(double t) const {
  PathPoint p;
  if (t < t0_) {  // before: straight line at the start velocity
    p.n = x0_ + v0_ * (t - t0_);
    p.n_dot = v0_;
    p.n_ddot = Eigen::VectorXd::Zero(x0_.size());
    return p;
  }
  if (t > t1_) {  // after: straight line at the end velocity
    p.n = x1_ + v1_ * (t - t1_);
    p.n_dot = v1_;
    p.n_ddot = Eigen::VectorXd::Zero(x0_.size());
    return p;
  }
  const double tau = t - t0_;
  p.n = x0_ + tau * (v0_ + tau * (c_ + tau * d_));
  p.n_dot = v0_ + tau * (2.0 * c_ + 3.0 * tau * d_);
  p.n_ddot = 2.0 * c_ + 6.0 * tau * d_;
  return p;
}

Eigen::VectorXd DefaultFinalVelocity(const Eigen::VectorXd& x0, const Eigen::VectorXd& v0, const Eigen::VectorXd& x1,
                                     double duration) {
  return 2.0 * (x1 - x0) / duration - v0;
}

std::string KeyframeSpline::Validate(const std::vector<double>& times, const std::vector<Eigen::VectorXd>& positions,
                                     const Options& options) {
  if (times.size() != positions.size()) return "as many times as positions are needed";
  if (times.size() < 2) return "at least two keys are needed";
  const long dim = positions[0].size();
  if (dim < 1) return "positions are empty";
  for (size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i])) return "key times must be finite";
    if (positions[i].size() != dim) return "every key needs a position of the same dimension";
    if (!positions[i].allFinite()) return "key positions must be finite";
    if (i > 0 && !(times[i] > times[i - 1])) return "key times must strictly increase";
  }
  for (const auto* v : {&options.start_velocity, &options.end_velocity})
    if (*v && ((*v)->size() != dim || !(*v)->allFinite())) return "end velocities must be finite and of the keys' dimension";
  return "";
}

KeyframeSpline::KeyframeSpline(std::vector<double> times, std::vector<Eigen::VectorXd> positions, Options options)
    : times_(std::move(times)), positions_(std::move(positions)) {
  assert(Validate(times_, positions_, options).empty());
  const int n = int(times_.size());
  const int dim = int(positions_[0].size());
  // The slopes m_i of a C² piecewise cubic solve a tridiagonal system; row i (inner key):
  //   h_i m_{i−1} + 2 (h_{i−1} + h_i) m_i + h_{i−1} m_{i+1} = 3 (h_i δ_{i−1} + h_{i−1} δ_i)
  // with h_i = t_{i+1} − t_i and δ_i = (x_{i+1} − x_i)/h_i (equal second derivatives from both
  // sides). End rows: m = the given velocity (clamped), or 2 m_0 + m_1 = 3 δ_0 and
  // m_{n−2} + 2 m_{n−1} = 3 δ_{n−2} (zero second derivative: natural).
  std::vector<double> h(n - 1);
  std::vector<Eigen::VectorXd> delta(n - 1);
  for (int i = 0; i + 1 < n; ++i) {
    h[i] = times_[i + 1] - times_[i];
    delta[i] = (positions_[i + 1] - positions_[i]) / h[i];
  }
  std::vector<double> lower(n, 0.0), diag(n, 0.0), upper(n, 0.0);
  std::vector<Eigen::VectorXd> rhs(n, Eigen::VectorXd::Zero(dim));
  if (options.start_velocity) {
    diag[0] = 1.0;
    rhs[0] = *options.start_velocity;
  } else {
    diag[0] = 2.0;
    upper[0] = 1.0;
    rhs[0] = 3.0 * delta[0];
  }
  for (int i = 1; i + 1 < n; ++i) {
    lower[i] = h[i];
    diag[i] = 2.0 * (h[i - 1] + h[i]);
    upper[i] = h[i - 1];
    rhs[i] = 3.0 * (h[i] * delta[i - 1] + h[i - 1] * delta[i]);
  }
  if (options.end_velocity) {
    diag[n - 1] = 1.0;
    lower[n - 1] = 0.0;
    rhs[n - 1] = *options.end_velocity;
  } else {
    lower[n - 1] = 1.0;
    diag[n - 1] = 2.0;
    rhs[n - 1] = 3.0 * delta[n - 2];
  }
  // Thomas algorithm (the matrix is diagonally dominant: no pivoting needed)
  for (int i = 1; i < n; ++i) {
    const double f = lower[i] / diag[i - 1];
    diag[i] -= f * upper[i - 1];
    rhs[i] -= f * rhs[i - 1];
  }
  slopes_.assign(n, Eigen::VectorXd());
  slopes_[n - 1] = rhs[n - 1] / diag[n - 1];
  for (int i = n - 2; i >= 0; --i) slopes_[i] = (rhs[i] - upper[i] * slopes_[i + 1]) / diag[i];
  for (int i = 0; i + 1 < n; ++i)
    segments_.emplace_back(times_[i], positions_[i], slopes_[i], times_[i + 1], positions_[i + 1], slopes_[i + 1]);
}

PathPoint KeyframeSpline::Evaluate(double t) const {
  if (t <= times_.front()) return segments_.front().Evaluate(t);
  if (t >= times_.back()) return segments_.back().Evaluate(t);
  // the segment holding t: the last key at or before it
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const int i = int(it - times_.begin()) - 1;
  return segments_[i].Evaluate(t);
}

PrerolledPath::PrerolledPath(std::shared_ptr<const Path> path, double start_time, const Eigen::VectorXd& position,
                             const Eigen::VectorXd& velocity, double path_start)
    : path_(std::move(path)),
      preroll_([&] {
        const PathPoint onset = path_->Evaluate(path_start);
        return HermiteSegment(start_time, position, velocity, path_start, onset.n, onset.n_dot);
      }()),
      path_start_(path_start) {}

PathPoint PrerolledPath::Evaluate(double t) const {
  return t < path_start_ ? preroll_.Evaluate(t) : path_->Evaluate(t);
}

}  // namespace wobble::control
