// An FFD body as loaded, in 2D or 3D: lattice, modes, mass points, drawing geometry, and the
// mass moments that make its dynamics cost O(D²) per step instead of O(N).
//
// This is the immutable "model" half (MuJoCo's mjModel); the state q, q̇ and contacts are in
// BodyState. Everything here is computed once per body and mode set.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "wobble/body/group.h"
#include "wobble/body/lattice.h"
#include "wobble/body/mode.h"
#include "wobble/body/surface_mesh.h"
#include "wobble/core/types.h"

namespace wobble {

// A polyline of the character's drawing geometry, in the body frame (Fig. 1.2: the table is
// three segments). Drawn, never simulated.
template <int Dim> struct PolylineN {
  std::vector<Eigen::Matrix<double, Dim, 1>> points;
  bool closed = false;
};
using Polyline = PolylineN<2>;

// What an object file describes.
template <int Dim> struct BodyDefN {
  std::string name;
  LatticeN<Dim> lattice;
  std::vector<Eigen::Matrix<double, Dim, 1>> mass_positions;  // body frame
  std::vector<double> masses;
  std::vector<PolylineN<Dim>> shapes;
  TriangleMeshN<Dim> mesh;  // a surface to draw (3D: a user's mesh), moved by the FFD; never simulated
};
using BodyDef = BodyDefN<2>;

// Mass moments: with l_k(γ) = b0_k + B_k γ the local position of point k, sums over the mass
// points that make every term of the dynamics a polynomial in γ of degree ≤ 2 (derivation in
// ARCHITECTURE.md). One layout per dimension, because the cross products differ.
template <int Dim> struct MassMomentsN;

// 2D: m = Σ m_k, c0 = Σ m_k b0_k, C = Σ m_k B_k, I0 = Σ m_k |b0_k|², e0 = Σ m_k B_kᵀ b0_k,
//   G = Σ m_k B_kᵀ B_k, h0 = Σ m_k B_kᵀ S b0_k, P = Σ m_k B_kᵀ S B_k.
//
// About the centre of mass the mode block of M is G_com = G − CᵀC/m, which does not depend on
// q at all (RᵀR = I): its Cholesky factor is made once here and every step reuses it
// (SolveMassSystem in kinematics.h).
template <> struct MassMomentsN<2> {
  double m = 0, I0 = 0;
  Eigen::Vector2d c0 = Eigen::Vector2d::Zero();
  Mat2D<double> C;
  VecD<double> e0, h0;
  MatD<double> G, P;
  MatD<double> G_com_factor;  // CholeskyInPlace(G − CᵀC/m); valid when G_com_positive
  bool G_com_positive = false;  // false: some mode combination moves no mass relative to the centre
};
using MassMoments = MassMomentsN<2>;

// 3D (B^d is column d of B_k, × the cross product):
//   m, c0 = Σ m_k b0_k, C = Σ m_k B_k (3 x D), G = Σ m_k B_kᵀ B_k, e0 = Σ m_k B_kᵀ b0_k,
//   S0 = Σ m_k b0_k b0_kᵀ, E_d = Σ m_k b0_k B^dᵀ, F_de = Σ m_k B^d B^eᵀ (3 x 3 each),
//   H0 = [Σ m_k b0_k × B^d]_d (3 x D), X_de = Σ m_k B^d × B^e (= −X_ed).
// The second moment K(γ) = Σ m_k l_k l_kᵀ = S0 + Σ_d γ_d (E_d + E_dᵀ) + Σ_de γ_d γ_e F_de gives
// the inertia tensor about the body origin, I(γ) = tr(K) 1 − K; dynamics/spatial_inertia.h has the rest.
template <> struct MassMomentsN<3> {
  double m = 0;
  Eigen::Vector3d c0 = Eigen::Vector3d::Zero();
  Mat3D<double> C, H0;
  VecD<double> e0;
  MatD<double> G;
  Eigen::Matrix3d S0 = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Matrix3d> E;  // D
  std::vector<Eigen::Matrix3d> F;  // D x D, at d*D + e
  std::vector<Eigen::Vector3d> X;  // D x D, at d*D + e
  MatD<double> G_com_factor;       // CholeskyInPlace(G − CᵀC/m), as in 2D
  bool G_com_positive = false;
};

// Mass points grouped by where they sit in the lattice, with interval bounds of their local
// positions: every l_k = b0_k + B_k γ of the group lies in the box centre(γ) ± half(γ) with
// centre = centre0 + centre_modes γ and half = half0 + half_modes |γ|. The ground scan skips a
// group whose box is above the ground, so a large body resting on its feet visits only the
// points near them (any basis: the bound needs no convex-hull property).
template <int Dim> struct PointClusterN {
  using Point = Eigen::Matrix<double, Dim, 1>;
  std::vector<int> points;  // ascending
  Point centre0 = Point::Zero(), half0 = Point::Zero();
  MatND<double, Dim> centre_modes, half_modes;  // Dim x D
};
using PointCluster = PointClusterN<2>;

// An FFD body as loaded: lattice, modes, mass points, drawing geometry, and the mass moments
// that make its dynamics cost O(D²) per step instead of O(N). One template serves the 2D body
// of the thesis and the 3D body of its §6.2 outlook.
template <int Dim> class BodyModelN {
 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  using ModeMatrix = MatND<double, Dim>;

  // Throws std::invalid_argument when the modes do not fit the lattice, a mass is not
  // positive and finite, or there are more than kMaxModes modes.
  BodyModelN(BodyDefN<Dim> def, std::vector<DeformationModeN<Dim>> modes);

  // This body with every mode's stiffness and damping zero (the fits and the adjoint apply
  // their own mode forces). A copy: nothing is recomputed, the moments do not depend on gains.
  BodyModelN WithoutModeGains() const {
    BodyModelN passive = *this;
    for (DeformationModeN<Dim>& m : passive.modes_) m.stiffness = m.damping = 0.0;
    return passive;
  }

  // Every mode's own stiffness K_d and damping c_d, as vectors (the gains the fits start from).
  void ModeGains(Eigen::VectorXd* stiffness, Eigen::VectorXd* damping) const {
    stiffness->resize(num_modes());
    damping->resize(num_modes());
    for (int d = 0; d < num_modes(); ++d) {
      (*stiffness)[d] = modes_[size_t(d)].stiffness;
      (*damping)[d] = modes_[size_t(d)].damping;
    }
  }

  static constexpr int dim() { return Dim; }
  const std::string& name() const { return def_.name; }
  const BodyDefN<Dim>& def() const { return def_; }
  const LatticeN<Dim>& lattice() const { return def_.lattice; }
  const std::vector<DeformationModeN<Dim>>& modes() const { return modes_; }
  int num_modes() const { return int(modes_.size()); }
  // velocities (the size of M): 3 + D in 2D (ṫ, θ̇, γ̇), 6 + D in 3D (ṫ, body ω, γ̇)
  int num_q() const { return NumVelocities<Dim>(num_modes()); }
  // positions: 3 + D in 2D (t, θ, γ), 7 + D in 3D (t, a unit quaternion, γ); group.h
  int num_positions() const { return NumPositions<Dim>(num_modes()); }
  int num_points() const { return int(def_.masses.size()); }
  double mass(int k) const { return def_.masses[k]; }
  const Point& lattice_coords(int k) const { return lattice_coords_[k]; }
  const MassMomentsN<Dim>& moments() const { return moments_; }

  // Rest local position b0_k and mode matrix B_k (Dim x D, column d = b^d_k) of mass point k.
  const Point& rest_local(int k) const { return rest_local_[k]; }
  Eigen::Map<const Eigen::Matrix<double, Dim, Eigen::Dynamic>> mode_matrix(int k) const {
    return {mode_rows_.data() + Dim * num_modes() * k, Dim, num_modes()};
  }

  // b0 and B of an arbitrary point given by its lattice coordinates (springs, drawing).
  void LocalBasis(const Point& st, Point* b0, ModeMatrix* B) const;

  // The same for the vertices of def().mesh, made once: drawing a deformed mesh is then
  // x_v = t + R (b0_v + B_v γ) per vertex, whatever the lattice's size.
  const Point& mesh_rest_local(int v) const { return mesh_rest_local_[v]; }
  Eigen::Map<const Eigen::Matrix<double, Dim, Eigen::Dynamic>> mesh_mode_matrix(int v) const {
    return {mesh_mode_rows_.data() + Dim * num_modes() * v, Dim, num_modes()};
  }

  // Rest control points (flat index), for the convex-hull ground test and drawing.
  const std::vector<Point>& rest_control() const { return rest_control_; }

  // The points in groups of about kPointsPerCluster; a single group for small bodies.
  static constexpr int kPointsPerCluster = 64;
  const std::vector<PointClusterN<Dim>>& clusters() const { return clusters_; }

 private:
  BodyDefN<Dim> def_;
  std::vector<DeformationModeN<Dim>> modes_;
  std::vector<Point> lattice_coords_, rest_local_, rest_control_;
  std::vector<double> mode_rows_;  // per point, column-major Dim x D
  std::vector<Point> mesh_rest_local_;
  std::vector<double> mesh_mode_rows_;  // per mesh vertex, as mode_rows_
  MassMomentsN<Dim> moments_;
  std::vector<PointClusterN<Dim>> clusters_;

  void BuildClusters();
};

using BodyModel = BodyModelN<2>;

extern template class BodyModelN<2>;
extern template class BodyModelN<3>;

}  // namespace wobble
