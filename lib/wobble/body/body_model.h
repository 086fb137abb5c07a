// An FFD body as loaded: lattice, modes, mass points, drawing geometry, and the mass moments
// that make its dynamics cost O(D²) per step instead of O(N).
//
// This is the immutable "model" half (MuJoCo's mjModel); the state q, q̇ and contacts are in
// BodyState. Everything here is computed once per body and mode set.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "wobble/body/lattice.h"
#include "wobble/body/mode.h"
#include "wobble/core/types.h"

namespace wobble {

// A polyline of the character's drawing geometry, in the body frame (Fig. 1.2: the table is
// three segments). Drawn, never simulated.
struct Polyline {
  std::vector<Eigen::Vector2d> points;
  bool closed = false;
};

// What an object file describes.
struct BodyDef {
  std::string name;
  Lattice lattice;
  std::vector<Eigen::Vector2d> mass_positions;  // body frame
  std::vector<double> masses;
  std::vector<Polyline> shapes;
};

// Mass moments of ARCHITECTURE.md: with l_k(γ) = b0_k + B_k γ the local position of point k,
//   m = Σ m_k, c0 = Σ m_k b0_k, C = Σ m_k B_k, I0 = Σ m_k |b0_k|², e0 = Σ m_k B_kᵀ b0_k,
//   G = Σ m_k B_kᵀ B_k, h0 = Σ m_k B_kᵀ S b0_k, P = Σ m_k B_kᵀ S B_k.
//
// About the centre of mass the mode block of M is G_com = G − CᵀC/m, which does not depend on
// q at all (RᵀR = I): its Cholesky factor is made once here and every step reuses it
// (SolveMassSystem in kinematics.h).
struct MassMoments {
  double m = 0, I0 = 0;
  Eigen::Vector2d c0 = Eigen::Vector2d::Zero();
  Mat2D<double> C;
  VecD<double> e0, h0;
  MatD<double> G, P;
  MatD<double> G_com_factor;  // CholeskyInPlace(G − CᵀC/m); valid when G_com_positive
  bool G_com_positive = false;  // false: some mode combination moves no mass relative to the centre
};

// Mass points grouped by where they sit in the lattice, with interval bounds of their local
// positions: every l_k = b0_k + B_k γ of the group lies in the box centre(γ) ± half(γ) with
// centre = centre0 + centre_modes γ and half = half0 + half_modes |γ|. The ground scan skips a
// group whose box is above the ground, so a large body resting on its feet visits only the
// points near them (any basis: the bound needs no convex-hull property).
struct PointCluster {
  std::vector<int> points;  // ascending
  Eigen::Vector2d centre0 = Eigen::Vector2d::Zero(), half0 = Eigen::Vector2d::Zero();
  Mat2D<double> centre_modes, half_modes;  // 2 x D
};

class BodyModel {
 public:
  // Throws std::invalid_argument when the modes do not fit the lattice, a mass is not
  // positive and finite, or there are more than kMaxModes modes.
  BodyModel(BodyDef def, std::vector<DeformationMode> modes);

  const std::string& name() const { return def_.name; }
  const BodyDef& def() const { return def_; }
  const Lattice& lattice() const { return def_.lattice; }
  const std::vector<DeformationMode>& modes() const { return modes_; }
  int num_modes() const { return int(modes_.size()); }
  int num_q() const { return kRigidDofs + num_modes(); }
  int num_points() const { return int(def_.masses.size()); }
  double mass(int k) const { return def_.masses[k]; }
  const Eigen::Vector2d& lattice_coords(int k) const { return lattice_coords_[k]; }
  const MassMoments& moments() const { return moments_; }

  // Rest local position b0_k and mode matrix B_k (2 x D, column d = b^d_k) of mass point k.
  const Eigen::Vector2d& rest_local(int k) const { return rest_local_[k]; }
  Eigen::Map<const Eigen::Matrix<double, 2, Eigen::Dynamic>> mode_matrix(int k) const {
    return {mode_rows_.data() + 2 * num_modes() * k, 2, num_modes()};
  }

  // b0 and B of an arbitrary point given by its lattice coordinates (springs, drawing).
  void LocalBasis(const Eigen::Vector2d& st, Eigen::Vector2d* b0, Mat2D<double>* B) const;

  // Rest control points L_ij (flat index), for the convex-hull ground test and drawing.
  const std::vector<Eigen::Vector2d>& rest_control() const { return rest_control_; }

  // The points in groups of about kPointsPerCluster; a single group for small bodies.
  static constexpr int kPointsPerCluster = 64;
  const std::vector<PointCluster>& clusters() const { return clusters_; }

 private:
  BodyDef def_;
  std::vector<DeformationMode> modes_;
  std::vector<Eigen::Vector2d> lattice_coords_, rest_local_, rest_control_;
  std::vector<double> mode_rows_;  // per point, column-major 2 x D
  MassMoments moments_;
  std::vector<PointCluster> clusters_;

  void BuildClusters();
};

}  // namespace wobble
