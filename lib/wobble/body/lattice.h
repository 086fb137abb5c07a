// The FFD control lattice of a body, in the body frame, in 2D (Faloutsos 1995) or 3D (its §6.2
// outlook; Sederberg & Parry's trivariate lattice).
//
// The lattice is a parallelepiped origin + Σ_a u_a axis_a, u in [0,1]^Dim, with a tensor
// product of (n_a + 1) control points per axis. The thesis puts the body frame's origin at the
// lattice's bottom-left point (§4.3), so the default origin is 0. Control point (i, j[, k]) —
// i along the first axis (s), j along the second (t), k along the third (u) — is stored at the
// row-major flat index (i*num(1) + j)*num(2) + k everywhere in wobble; in 2D that is i*(m+1)+j.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products of 3D lattices and modes
#include <Eigen/LU>
#include <array>
#include <type_traits>
#include <vector>

#include "wobble/core/basis.h"

namespace wobble {

template <int Dim> class LatticeN {
  static_assert(Dim == 2 || Dim == 3, "lattices are 2D or 3D");

 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  using Axes = std::array<Point, Dim>;
  using Sizes = std::array<int, Dim>;
  using Cell = std::array<int, Dim>;  // (i, j[, k])

  // The unit square (cube) with 4 control points per axis, Bernstein.
  LatticeN();
  // Throws std::invalid_argument when the axes are not finite or do not span the space, or a
  // size does not suit the basis (Basis1D).
  LatticeN(const Point& origin, const Axes& axes, const Sizes& sizes, BasisKind basis);
  // 2D: a lattice with num_s x num_t control points (4 x 4 by default).
  template <int D = Dim, std::enable_if_t<D == 2, int> = 0>
  LatticeN(const Point& origin, const Point& axis_s, const Point& axis_t, int num_s = 4, int num_t = 4,
           BasisKind basis = BasisKind::kBernstein)
      : LatticeN(origin, Axes{axis_s, axis_t}, Sizes{num_s, num_t}, basis) {}

  static constexpr int dim() { return Dim; }
  static constexpr int kMaxControlPoints = 1 << 16;
  int num(int axis) const { return basis_[axis].size(); }  // n_axis + 1
  Sizes sizes() const;
  int size() const;  // number of control points
  BasisKind basis() const { return basis_[0].kind(); }
  const Point& origin() const { return origin_; }
  const Point& axis(int a) const { return axes_[a]; }
  const Axes& axes() const { return axes_; }

  int FlatIndex(const Cell& cell) const;
  Cell CellOf(int flat) const;

  // The 2D names of the thesis.
  int num_s() const { return num(0); }
  int num_t() const { return num(1); }
  const Point& axis_s() const { return axes_[0]; }
  const Point& axis_t() const { return axes_[1]; }
  int Index(int i, int j) const { return i * num(1) + j; }
  Point RestPoint(int i, int j) const { return RestPoint(Index(i, j)); }

  // Rest (undeformed) control point, by flat index: origin + Σ_a abscissa_a axis_a.
  Point RestPoint(int flat) const;
  std::vector<Point> RestPoints() const;

  // Tensor-product weights Π_a B_{i_a}(u_a) of every control point (flat index), Eq. 4.1.
  void Weights(const Point& u, double* w) const;
  std::vector<double> Weights(const Point& u) const;

  // Lattice coordinates u of a body-frame point p: the solution of Σ_a u_a axis_a = p − origin
  // (Sederberg & Parry's s = (T x U)·(X − X0) / ((T x U)·S) is Cramer's rule for it, §2.2.2).
  Point LocalCoords(const Point& p) const;

  // Body-frame position of lattice coordinates u under control points `control` (size()
  // entries, flat index): Σ control_c W_c(u).
  Point Evaluate(const std::vector<Point>& control, const Point& u) const;

 private:
  Point origin_;
  Axes axes_;
  Eigen::Matrix<double, Dim, Dim> to_local_;  // inverse of the matrix whose columns are the axes
  std::array<Basis1D, Dim> basis_;
};

using Lattice = LatticeN<2>;

extern template class LatticeN<2>;
extern template class LatticeN<3>;

}  // namespace wobble
