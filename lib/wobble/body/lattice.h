// The FFD control lattice of a body, in the body frame.
//
// The lattice is a parallelogram origin + s*axis_s + t*axis_t, (s, t) in [0,1]^2, with
// (n+1) x (m+1) control points. The thesis puts the body frame's origin at the lattice's
// bottom-left point (§4.3), so the default origin is (0, 0). Control point (i, j) — i along
// s, j along t — is stored at flat index i*(m+1)+j everywhere in wobble.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "wobble/core/basis.h"

namespace wobble {

class Lattice {
 public:
  Lattice() : Lattice(Eigen::Vector2d::Zero(), Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1)) {}
  // A lattice with num_s x num_t control points (4 x 4 by default) of the given basis.
  Lattice(const Eigen::Vector2d& origin, const Eigen::Vector2d& axis_s, const Eigen::Vector2d& axis_t,
          int num_s = 4, int num_t = 4, BasisKind basis = BasisKind::kBernstein);

  int num_s() const { return basis_s_.size(); }  // n + 1
  int num_t() const { return basis_t_.size(); }  // m + 1
  int size() const { return num_s() * num_t(); }
  int Index(int i, int j) const { return i * num_t() + j; }
  BasisKind basis() const { return basis_s_.kind(); }
  const Eigen::Vector2d& origin() const { return origin_; }
  const Eigen::Vector2d& axis_s() const { return axis_s_; }
  const Eigen::Vector2d& axis_t() const { return axis_t_; }

  // Rest (undeformed) control point L_ij in the body frame.
  Eigen::Vector2d RestPoint(int i, int j) const;
  std::vector<Eigen::Vector2d> RestPoints() const;

  // Tensor-product weights B_i(s) B_j(t) of every control point (flat index), Eq. 4.1.
  void Weights(const Eigen::Vector2d& st, double* w) const;
  std::vector<double> Weights(const Eigen::Vector2d& st) const;

  // Lattice coordinates (s, t) of a body-frame point: the 2D form of Sederberg & Parry's
  // s = (T x U)·(X - X0) / ((T x U)·S) (§2.2.2), with the perpendicular in place of the cross product.
  Eigen::Vector2d LocalCoords(const Eigen::Vector2d& p) const;

  // Body-frame position of lattice coordinates (s, t) under control points `control`
  // (size() entries, flat index): Σ_ij control_ij B_i(s) B_j(t).
  Eigen::Vector2d Evaluate(const std::vector<Eigen::Vector2d>& control, const Eigen::Vector2d& st) const;

 private:
  Eigen::Vector2d origin_, axis_s_, axis_t_;
  Basis1D basis_s_, basis_t_;
};

}  // namespace wobble
