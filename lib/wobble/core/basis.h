// Univariate basis functions of the free-form deformation lattice.
//
// A lattice dimension with n+1 control points uses either the Bernstein basis of degree n
// (Faloutsos 1995, Eq. 4.1; the thesis' default on a 4x4 lattice) or a clamped uniform cubic
// B-spline over the n+1 control points (§4.3: C2 continuity on larger lattices). Both are a
// partition of unity with non-negative weights, so a deformed point stays inside the convex
// hull of the control points it depends on.
#pragma once

#include <string>
#include <vector>

namespace wobble {

enum class BasisKind { kBernstein, kCubicBSpline };

std::string BasisName(BasisKind kind);
// Parses "bernstein" or "bspline"; returns false for anything else.
bool ParseBasisKind(const std::string& text, BasisKind* kind);

// Binomial coefficient C(n, k) of Eq. 4.1, exact in double for n < 60.
double Binomial(int n, int k);

// One lattice dimension: which basis, and how many control points (degree + 1 for Bernstein).
class Basis1D {
 public:
  Basis1D() = default;
  // num_control >= 2 for Bernstein, >= 4 for the cubic B-spline.
  Basis1D(BasisKind kind, int num_control);

  BasisKind kind() const { return kind_; }
  int size() const { return num_control_; }

  // Weights w[0..size()-1] at u in [0, 1] (clamped outside).
  void Weights(double u, double* w) const;
  std::vector<double> Weights(double u) const;

  // Parameter value a control point "belongs to": i/n for Bernstein, the Greville abscissa
  // for the B-spline. Rest control points placed at these values make the undeformed lattice
  // the identity map (linear precision), so a point's lattice coordinates equal its position.
  double Abscissa(int i) const;

 private:
  BasisKind kind_ = BasisKind::kBernstein;
  int num_control_ = 4;
  std::vector<double> knots_;  // B-spline only
};

}  // namespace wobble
