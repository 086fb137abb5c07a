#include "wobble/body/lattice.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace wobble {

template <int Dim> LatticeN<Dim>::LatticeN() {
  Axes unit;
  for (int a = 0; a < Dim; ++a) unit[a] = Point::Unit(a);
  Sizes four;
  four.fill(4);
  *this = LatticeN(Point::Zero(), unit, four, BasisKind::kBernstein);
}

template <int Dim>
LatticeN<Dim>::LatticeN(const Point& origin, const Axes& axes, const Sizes& sizes, BasisKind basis)
    : origin_(origin), axes_(axes) {
  // bounded before anything is sized from it: the weights of every point are stored per body
  double count = 1.0;
  for (int a = 0; a < Dim; ++a) count *= double(sizes[a]);
  if (!(count <= kMaxControlPoints))
    throw std::invalid_argument("a lattice of " +
                                (count < 1e18 ? std::to_string((long long)count) : std::string("over 10^18")) +
                                " control points; at most " +
                                std::to_string(kMaxControlPoints) + " are supported");
  Eigen::Matrix<double, Dim, Dim> frame;
  double scale = 1.0;
  for (int a = 0; a < Dim; ++a) {
    frame.col(a) = axes[a];
    scale *= axes[a].norm();
    basis_[a] = Basis1D(basis, sizes[a]);
  }
  // the volume spanned, relative to the product of the axis lengths: 0 for parallel axes
  const double volume = frame.determinant();
  if (!std::isfinite(volume) || !std::isfinite(scale) || !(std::abs(volume) > 1e-12 * scale))
    throw std::invalid_argument(Dim == 2 ? "lattice axes must be finite and span the plane"
                                         : "lattice axes must be finite and span space");
  to_local_ = frame.inverse();
}

template <int Dim> typename LatticeN<Dim>::Sizes LatticeN<Dim>::sizes() const {
  Sizes s;
  for (int a = 0; a < Dim; ++a) s[a] = num(a);
  return s;
}

template <int Dim> int LatticeN<Dim>::size() const {
  int n = 1;
  for (int a = 0; a < Dim; ++a) n *= num(a);
  return n;
}

template <int Dim> int LatticeN<Dim>::FlatIndex(const Cell& cell) const {
  int flat = 0;
  for (int a = 0; a < Dim; ++a) flat = flat * num(a) + cell[a];
  return flat;
}

template <int Dim> typename LatticeN<Dim>::Cell LatticeN<Dim>::CellOf(int flat) const {
  Cell cell;
  for (int a = Dim - 1; a >= 0; --a) {
    cell[a] = flat % num(a);
    flat /= num(a);
  }
  return cell;
}

template <int Dim> typename LatticeN<Dim>::Point LatticeN<Dim>::RestPoint(int flat) const {
  const Cell cell = CellOf(flat);
  Point p = origin_;
  for (int a = 0; a < Dim; ++a) p += basis_[a].Abscissa(cell[a]) * axes_[a];
  return p;
}

template <int Dim> std::vector<typename LatticeN<Dim>::Point> LatticeN<Dim>::RestPoints() const {
  std::vector<Point> points(size());
  for (int c = 0; c < size(); ++c) points[c] = RestPoint(c);
  return points;
}

template <int Dim> void LatticeN<Dim>::Weights(const Point& u, double* w) const {
  // setup-time code (bodies precompute their weights), so plain vectors are fine here
  std::array<std::vector<double>, Dim> per_axis;
  for (int a = 0; a < Dim; ++a) per_axis[a] = basis_[a].Weights(u[a]);
  for (int c = 0; c < size(); ++c) {
    const Cell cell = CellOf(c);
    double product = 1.0;
    for (int a = 0; a < Dim; ++a) product *= per_axis[a][cell[a]];
    w[c] = product;
  }
}

template <int Dim> std::vector<double> LatticeN<Dim>::Weights(const Point& u) const {
  std::vector<double> w(size());
  Weights(u, w.data());
  return w;
}

template <int Dim> typename LatticeN<Dim>::Point LatticeN<Dim>::LocalCoords(const Point& p) const {
  return to_local_ * (p - origin_);
}

template <int Dim>
typename LatticeN<Dim>::Point LatticeN<Dim>::Evaluate(const std::vector<Point>& control, const Point& u) const {
  const std::vector<double> w = Weights(u);
  Point p = Point::Zero();
  for (int c = 0; c < size(); ++c) p += w[c] * control[c];
  return p;
}

template class LatticeN<2>;
template class LatticeN<3>;

}  // namespace wobble
