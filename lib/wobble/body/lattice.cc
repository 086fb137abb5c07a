#include "wobble/body/lattice.h"

#include <cmath>
#include <stdexcept>

namespace wobble {

namespace {
Eigen::Vector2d Perp(const Eigen::Vector2d& v) { return Eigen::Vector2d(-v.y(), v.x()); }
}  // namespace

Lattice::Lattice(const Eigen::Vector2d& origin, const Eigen::Vector2d& axis_s, const Eigen::Vector2d& axis_t,
                 int num_s, int num_t, BasisKind basis)
    : origin_(origin), axis_s_(axis_s), axis_t_(axis_t), basis_s_(basis, num_s), basis_t_(basis, num_t) {
  const double area = axis_s.x() * axis_t.y() - axis_s.y() * axis_t.x();
  if (!(std::abs(area) > 1e-12 * axis_s.squaredNorm() * axis_t.squaredNorm()) || !std::isfinite(area))
    throw std::invalid_argument("lattice axes must be finite and span the plane");
}

Eigen::Vector2d Lattice::RestPoint(int i, int j) const {
  return origin_ + basis_s_.Abscissa(i) * axis_s_ + basis_t_.Abscissa(j) * axis_t_;
}

std::vector<Eigen::Vector2d> Lattice::RestPoints() const {
  std::vector<Eigen::Vector2d> points(size());
  for (int i = 0; i < num_s(); ++i)
    for (int j = 0; j < num_t(); ++j) points[Index(i, j)] = RestPoint(i, j);
  return points;
}

void Lattice::Weights(const Eigen::Vector2d& st, double* w) const {
  // setup-time code (bodies precompute their weights), so plain vectors are fine here
  const std::vector<double> ws = basis_s_.Weights(st.x()), wt = basis_t_.Weights(st.y());
  for (int i = 0; i < num_s(); ++i)
    for (int j = 0; j < num_t(); ++j) w[Index(i, j)] = ws[i] * wt[j];
}

std::vector<double> Lattice::Weights(const Eigen::Vector2d& st) const {
  std::vector<double> w(size());
  Weights(st, w.data());
  return w;
}

Eigen::Vector2d Lattice::LocalCoords(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - origin_;
  const Eigen::Vector2d t_perp = Perp(axis_t_), s_perp = Perp(axis_s_);
  return Eigen::Vector2d(t_perp.dot(d) / t_perp.dot(axis_s_), s_perp.dot(d) / s_perp.dot(axis_t_));
}

Eigen::Vector2d Lattice::Evaluate(const std::vector<Eigen::Vector2d>& control, const Eigen::Vector2d& st) const {
  const std::vector<double> w = Weights(st);
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  for (int k = 0; k < size(); ++k) p += w[k] * control[k];
  return p;
}

}  // namespace wobble
