// An FFD body as loaded, in 2D or 3D: lattice, modes, mass points, drawing geometry, and the
// mass moments that make its dynamics cost O(D²) per step instead of O(N).
//
// This is the immutable "model" half (MuJoCo's mjModel); the state q, q̇ and contacts are in
// BodyState. Everything here is computed once per body and mode set.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
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
  // G_com⁻¹, made once from the factor: G_com is constant, so the step's solves with it are
  // products, as Witkin & Welch 1990 precompute the inverse W of their constant mass matrix
  // (Eq. 4–5: R̈ = Q W); and the range of the factor's pivots, for the condition estimate.
  MatD<double> G_com_inverse;
  double G_com_pivot_lo = 0.0, G_com_pivot_hi = 0.0;
};

// Mass points grouped by where they sit in the lattice, with interval bounds of their local
// positions: every l_k = b0_k + B_k γ of the group lies in the box centre(γ) ± half(γ) with
// centre = centre0 + centre_modes γ and half = half0 + half_modes |γ| (any basis: the bound
// needs no convex-hull property). The groups fix the ground scan's order; the scan skips by
// the same bounds over the finer nodes of PointTreeN (below).
template <int Dim> struct PointClusterN {
  using Point = Eigen::Matrix<double, Dim, 1>;
  std::vector<int> points;  // ascending
  Point centre0 = Point::Zero(), half0 = Point::Zero();
  MatND<double, Dim> centre_modes, half_modes;  // Dim x D
};
using PointCluster = PointClusterN<2>;

// A tree of such interval bounds over the mass points of a large body (more than one point
// group), for the ground scan: each node bounds a range of the scan order, split at the group
// boundary nearest its middle, else the middle while halves shrink, down to kLeafPoints.
// Nodes are stored in preorder with `skip` (the node after the subtree), so a scan that rejects
// a node jumps past everything below it. A node's numbers sit at bounds[i * stride]: the
// centres of b0 and of each mode column (width = Dim (D + 1) numbers: [centre0, centre_modes
// column 0, ...]), the half widths in the same layout, then per axis the largest
// |centre| + half over the mode columns (for a coarse first test, PlaneReach).
template <int Dim> struct PointTreeN {
  static constexpr int kLeafPoints = 4;
  std::uint64_t serial = 0;  // unique per tree built (copies share it): a scan memo's key
  int width = 0, stride = 0;
  std::vector<double> bounds;
  std::vector<int> skip;
  std::vector<int> first, last;  // a leaf's points: leaf_ranks[first, last); empty for inner nodes
  std::vector<int> leaf_ranks;   // ascending within a leaf
  std::vector<int> by_rank;      // the scan order (the clusters', each ascending): rank -> point
};

// What the last full walk of a point tree against a plane found, kept with the body's state
// between steps (BodyState::scan_memo): the plane test's numbers (PlaneReach's), the leaves that
// reached, and the least amount by which a rejected node's bound cleared the margin. A body at
// rest moves so little from step to step that those leaves still hold every point that can
// reach (PlaneReach::StillCovers) for many steps: the scan then skips the walk.
template <int Dim> struct PlaneScanMemo {
  bool valid = false;
  std::uint64_t tree = 0;  // the serial of the tree walked
  int width = 0;           // the tree's: Dim (D + 1)
  double offset = 0.0, margin = 0.0;
  double slack = 0.0;  // min over rejected nodes of (bound − margin); +inf when none was
  double w[Dim * (kMaxModes + 1)] = {}, coarse[Dim] = {};
  std::vector<int> leaves;  // node indices, in walk order
};

// Whether a node of the tree may reach below a plane of body-frame normal n at offset
// n·(t − p) (a point's height is offset + n·l): l lies in centre(γ) ± half(γ), so its height is
// at least offset + w·centre − |w|·half with w = [n, γ_0 n, …], two dot products over the node's
// numbers. A coarse test first, offset + n·centre0 − |n|·half0 − ‖γ‖₁ |n|·ρ with ρ the node's
// largest |centre| + half over the mode columns (Dim numbers), rejects most nodes of a body at
// rest; an inner node is answered by it alone (the full test rarely rejects what it lets
// through, and the children are tested anyway), a leaf by both. Decisions on plain values: a node counts as reaching when its bound is below a margin,
// 1e-10 of the scale of t, p and the body (≥ the rounding of the bound and of the points' own
// height test by far), so the scan visits every point that the test of every point finds.
template <int Dim> class PlaneReach {
 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  // gamma_of(d): the amplitude γ_d; scale: |t|₁ + |p|₁
  template <class GammaOf>
  PlaneReach(const PointTreeN<Dim>& tree, int D, const Point& n, double offset, double scale, GammaOf&& gamma_of)
      : width_(tree.width), offset_(offset) {
    const Point n_abs = n.cwiseAbs();
    double gamma_norm = 0.0, extent = 0.0;
    const double* root = tree.bounds.data();
    for (int block = 0; block <= D; ++block) {
      const double gamma = block == 0 ? 1.0 : double(gamma_of(block - 1));
      for (int a = 0; a < Dim; ++a) {
        w_[Dim * block + a] = gamma * n[a];
        w_abs_[Dim * block + a] = std::abs(gamma) * n_abs[a];
        extent += std::abs(gamma) * (std::abs(root[Dim * block + a]) + root[tree.width + Dim * block + a]);
      }
      if (block > 0) gamma_norm += std::abs(gamma);
    }
    for (int a = 0; a < Dim; ++a) coarse_[a] = gamma_norm * n_abs[a];
    margin_ = 1e-10 * (scale + std::abs(offset) + extent);
  }
  bool operator()(const double* box, bool leaf) const { return Lower(box, leaf) < margin_; }
  // The bound that decides a node: the coarse one, and for a leaf the full one if the coarse
  // one lets it through.
  double Lower(const double* box, bool leaf) const {
    const double* half = box + width_;
    const double* rho = half + width_;
    double lower = offset_;
    for (int a = 0; a < Dim; ++a) lower += w_[a] * box[a] - w_abs_[a] * half[a] - coarse_[a] * rho[a];
    if (!(lower < margin_) || !leaf) return lower;
    lower = offset_;
    for (int j = 0; j < width_; ++j) lower += w_[j] * box[j] - w_abs_[j] * half[j];
    return lower;
  }
  double margin() const { return margin_; }

  // Saves this test's numbers in *memo (the walk fills in leaves and slack).
  void Remember(const PointTreeN<Dim>& tree, PlaneScanMemo<Dim>* memo) const {
    memo->tree = tree.serial;
    memo->width = width_;
    memo->offset = offset_;
    memo->margin = margin_;
    std::copy(w_, w_ + width_, memo->w);
    std::copy(coarse_, coarse_ + Dim, memo->coarse);
  }
  // Whether every node the memo's walk rejected is still rejected by this test, so that the
  // memo's leaves hold every point that can reach. Both bounds of a node are affine in
  // (offset, w, coarse) with coefficients |centre| + half (and ρ) of the node, at most the
  // root's (each node's boxes lie in its parent's): a node's bound moved by at most
  //   Δ = |Δoffset| + Σ_j |Δw_j| (|centre_j| + half_j)_root + Σ_a |Δcoarse_a| ρ_root,a.
  // A rejected node had bound ≥ margin_then + slack; it is still clear of the plane by more
  // than this test's margin when margin_then + slack − Δ ≥ margin_now (Δ widened by 1e-9 for
  // its own rounding; NaN or inf anywhere answers no).
  bool StillCovers(const PlaneScanMemo<Dim>& memo, const PointTreeN<Dim>& tree) const {
    if (!memo.valid || memo.tree != tree.serial || memo.width != width_) return false;
    const double* root = tree.bounds.data();
    const double* rho = root + 2 * width_;
    double delta = std::abs(offset_ - memo.offset);
    for (int j = 0; j < width_; ++j) delta += std::abs(w_[j] - memo.w[j]) * (std::abs(root[j]) + root[width_ + j]);
    for (int a = 0; a < Dim; ++a) delta += std::abs(coarse_[a] - memo.coarse[a]) * rho[a];
    return memo.margin + memo.slack - delta * (1.0 + 1e-9) >= margin_;
  }

 private:
  int width_;
  double offset_, margin_ = 0.0;
  double w_[Dim * (kMaxModes + 1)], w_abs_[Dim * (kMaxModes + 1)], coarse_[Dim];
};

// A per-point bound before a scan's exact test of a point against a plane, in the body frame
// as PlaneReach: the point's height offset + n·l_k, l_k = b0_k + B_k γ, is at least
// offset + n·b0_k − max_a |n_a| ‖γ‖₁ mode_reach(k) (n = Rᵀ·normal). A point
// counts as clear only when that bound is above a margin of 1e-10 of the scale of t, p, the
// body and γ (as PlaneReach's: far above the rounding of the bound and of the point's own height
// test), so a point the scan skips is one its exact test rejects. Costs Dim + 1 products a
// point instead of the position's Dim (D + Dim): most points of a resting body are far above.
template <int Dim> class PointClearOfPlane {
 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  // gamma_norm: ‖γ‖₁; scale: |t|₁ + |p|₁
  PointClearOfPlane(double rest_extent, double max_mode_reach, const Point& n, double offset, double scale,
                    double gamma_norm)
      : n_(n), offset_(offset) {
    const double n_max = n.cwiseAbs().maxCoeff();  // 1 for a unit n, up to rounding
    gamma_norm_ = gamma_norm * n_max;
    margin_ = 1e-10 * (scale + std::abs(offset) + n_max * (rest_extent + gamma_norm * max_mode_reach));
  }
  bool operator()(const Point& b0, double mode_reach) const {
    return offset_ + n_.dot(b0) - gamma_norm_ * mode_reach > margin_;  // NaN: not clear
  }

 private:
  Point n_;
  double offset_, gamma_norm_, margin_;
};

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

  // max_d ‖b^d_k‖₁, the largest mode column of point k: for any n with |n_a| ≤ 1 its height
  // n·l_k is within ‖γ‖₁ mode_reach(k) of n·b0_k, a bound the ground scan tests before the
  // exact position (PointClearOfPlane).
  double mode_reach(int k) const { return mode_reach_[size_t(k)]; }
  // max_k ‖b0_k‖₁ and max_k mode_reach(k), for the scale of that bound's rounding margin
  double rest_extent() const { return rest_extent_; }
  double max_mode_reach() const { return max_mode_reach_; }

  // Rest control points (flat index), for the convex-hull ground test and drawing.
  const std::vector<Point>& rest_control() const { return rest_control_; }

  // The points in groups of about kPointsPerCluster; a single group for small bodies.
  static constexpr int kPointsPerCluster = 64;
  const std::vector<PointClusterN<Dim>>& clusters() const { return clusters_; }
  const PointTreeN<Dim>& point_tree() const { return tree_; }

  // Calls visit(k) for every point of the tree's leaves whose node (and every ancestor)
  // reaches(bounds, leaf) accepts, in the scan order of the clusters (the order of a scan of every
  // point group), so sums over the visited points add in the same order whatever is skipped.
  // `reaches` must be conservative; it may answer an inner node (leaf false) with a cheaper,
  // looser bound, since a wrong "yes" there costs only the children's tests. visit must not
  // start another scan on this thread.
  template <class Reaches, class Visit> void ForEachPointInReach(Reaches&& reaches, Visit&& visit) const {
    thread_local std::vector<int> leaves;
    CollectLeavesInReach(reaches, &leaves);
    VisitLeaves(leaves, visit);
  }
  // The same for a plane, with the memo of the last walk (PlaneScanMemo): when the memo still
  // covers this test, its leaves are visited without a walk; otherwise the tree is walked and
  // the memo rewritten. Either way visit(k) sees the same points in the same order as
  // ForEachPointInReach, except points of leaves that the walk would have rejected, which the
  // caller's exact test rejects too.
  template <class Visit>
  void ForEachPointInPlaneReach(const PlaneReach<Dim>& reach, PlaneScanMemo<Dim>* memo, Visit&& visit) const {
    if (!reach.StillCovers(*memo, tree_)) {
      double slack = std::numeric_limits<double>::infinity();
      CollectLeavesInReach(
          [&](const double* box, bool leaf) {
            const double lower = reach.Lower(box, leaf);
            if (lower < reach.margin()) return true;
            slack = std::min(slack, lower - reach.margin());
            return false;
          },
          &memo->leaves);
      reach.Remember(tree_, memo);
      memo->slack = slack;
      memo->valid = slack == slack;  // a NaN bound: walk again next time
    }
    VisitLeaves(memo->leaves, visit);
  }

 private:
  // The leaves (node indices, in walk order) of the nodes that reaches() accepts with every
  // ancestor; a rejected node's subtree is skipped.
  template <class Reaches> void CollectLeavesInReach(Reaches&& reaches, std::vector<int>* leaves) const {
    leaves->clear();
    const int n = int(tree_.skip.size());
    for (int i = 0; i < n;) {
      const bool leaf = tree_.first[size_t(i)] < tree_.last[size_t(i)];
      if (!reaches(tree_.bounds.data() + size_t(i) * size_t(tree_.stride), leaf)) {
        i = tree_.skip[size_t(i)];
        continue;
      }
      if (leaf) leaves->push_back(i);
      ++i;
    }
  }
  // visit(k) for the points of those leaves in scan order.
  template <class Visit> void VisitLeaves(const std::vector<int>& leaves, Visit&& visit) const {
    thread_local std::vector<int> ranks;
    ranks.clear();
    bool sorted = true;
    for (int i : leaves) {
      const int first = tree_.first[size_t(i)], last = tree_.last[size_t(i)];
      if (!ranks.empty() && tree_.leaf_ranks[size_t(first)] < ranks.back()) sorted = false;
      ranks.insert(ranks.end(), tree_.leaf_ranks.begin() + first, tree_.leaf_ranks.begin() + last);
    }
    if (!sorted) std::sort(ranks.begin(), ranks.end());
    for (int r : ranks) visit(tree_.by_rank[size_t(r)]);
  }

  BodyDefN<Dim> def_;
  std::vector<DeformationModeN<Dim>> modes_;
  std::vector<Point> lattice_coords_, rest_local_, rest_control_;
  std::vector<double> mode_rows_;  // per point, column-major Dim x D
  std::vector<double> mode_reach_;
  double rest_extent_ = 0.0, max_mode_reach_ = 0.0;
  std::vector<Point> mesh_rest_local_;
  std::vector<double> mesh_mode_rows_;  // per mesh vertex, as mode_rows_
  MassMomentsN<Dim> moments_;
  std::vector<PointClusterN<Dim>> clusters_;
  PointTreeN<Dim> tree_;

  void BuildClusters();
  void BuildTree();
};

using BodyModel = BodyModelN<2>;

extern template class BodyModelN<2>;
extern template class BodyModelN<3>;

}  // namespace wobble
