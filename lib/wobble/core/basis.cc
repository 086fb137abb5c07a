#include "wobble/core/basis.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

namespace wobble {

std::string BasisName(BasisKind kind) {
  return kind == BasisKind::kBernstein ? "bernstein" : "bspline";
}

bool ParseBasisKind(const std::string& text, BasisKind* kind) {
  if (text == "bernstein") {
    *kind = BasisKind::kBernstein;
  } else if (text == "bspline") {
    *kind = BasisKind::kCubicBSpline;
  } else {
    return false;
  }
  return true;
}

double Binomial(int n, int k) {
  if (k < 0 || k > n) return 0.0;
  k = std::min(k, n - k);
  double c = 1.0;
  for (int i = 1; i <= k; ++i) c = c * (n - k + i) / i;
  return std::round(c);
}

Basis1D::Basis1D(BasisKind kind, int num_control) : kind_(kind), num_control_(num_control) {
  if (kind == BasisKind::kBernstein && num_control < 2)
    throw std::invalid_argument("a Bernstein lattice dimension needs at least 2 control points");
  if (kind == BasisKind::kCubicBSpline) {
    if (num_control < 4)
      throw std::invalid_argument("a cubic B-spline lattice dimension needs at least 4 control points");
    // clamped uniform knot vector: 4 zeros, uniform interior knots, 4 ones
    const int spans = num_control - 3;
    knots_.assign(4, 0.0);
    for (int k = 1; k < spans; ++k) knots_.push_back(double(k) / spans);
    knots_.insert(knots_.end(), 4, 1.0);
  }
}

void Basis1D::Weights(double u, double* w) const {
  u = std::clamp(u, 0.0, 1.0);
  const int n = num_control_ - 1;
  if (kind_ == BasisKind::kBernstein) {
    // Eq. 4.1: C(n,i) (1-u)^(n-i) u^i
    for (int i = 0; i <= n; ++i)
      w[i] = Binomial(n, i) * std::pow(1.0 - u, n - i) * std::pow(u, i);
    return;
  }
  // Cox–de Boor recursion for degree 3; the last span is closed at u = 1.
  const int p = 3;
  int span = p;
  while (span < n && u >= knots_[span + 1]) ++span;
  double basis[p + 1] = {1.0, 0.0, 0.0, 0.0};
  double left[p + 1], right[p + 1];
  for (int j = 1; j <= p; ++j) {
    left[j] = u - knots_[span + 1 - j];
    right[j] = knots_[span + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double tmp = basis[r] / (right[r + 1] + left[j - r]);
      basis[r] = saved + right[r + 1] * tmp;
      saved = left[j - r] * tmp;
    }
    basis[j] = saved;
  }
  std::fill(w, w + num_control_, 0.0);
  for (int r = 0; r <= p; ++r) w[span - p + r] = basis[r];
}

std::vector<double> Basis1D::Weights(double u) const {
  std::vector<double> w(num_control_);
  Weights(u, w.data());
  return w;
}

double Basis1D::Abscissa(int i) const {
  assert(i >= 0 && i < num_control_);
  if (kind_ == BasisKind::kBernstein) return double(i) / (num_control_ - 1);
  return (knots_[i + 1] + knots_[i + 2] + knots_[i + 3]) / 3.0;
}

}  // namespace wobble
