#include "wobble/body/body_model.h"

#include "wobble/core/cholesky.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <tuple>
#include <stdexcept>

namespace wobble {

namespace {

template <int Dim> std::string SizeText(const std::array<int, Dim>& sizes) {
  std::string text;
  for (int a = 0; a < Dim; ++a) text += (a ? "x" : "") + std::to_string(sizes[a]);
  return text;
}

// Sizes the moments for D modes.
void StartMoments(int D, MassMomentsN<2>* mm) {
  mm->C.setZero(2, D);
  mm->e0.setZero(D);
  mm->h0.setZero(D);
  mm->G.setZero(D, D);
  mm->P.setZero(D, D);
}
void StartMoments(int D, MassMomentsN<3>* mm) {
  mm->C.setZero(3, D);
  mm->H0.setZero(3, D);
  mm->e0.setZero(D);
  mm->G.setZero(D, D);
  mm->E.assign(D, Eigen::Matrix3d::Zero());
  mm->F.assign(size_t(D) * D, Eigen::Matrix3d::Zero());
  mm->X.assign(size_t(D) * D, Eigen::Vector3d::Zero());
}

// Adds mass point (m, b0, B) to the moments (definitions in body_model.h).
void AddPoint(double m, const Eigen::Vector2d& b0, const Mat2D<double>& B, MassMomentsN<2>* mm) {
  const int D = int(B.cols());
  const Eigen::Vector2d Sb0(-b0.y(), b0.x());
  Mat2D<double> SB(2, D);
  SB.row(0) = -B.row(1);
  SB.row(1) = B.row(0);
  mm->m += m;
  mm->c0 += m * b0;
  mm->I0 += m * b0.squaredNorm();
  mm->C += m * B;
  mm->e0 += m * B.transpose() * b0;
  mm->h0 += m * B.transpose() * Sb0;
  mm->G += m * B.transpose() * B;
  mm->P += m * B.transpose() * SB;
}
void AddPoint(double m, const Eigen::Vector3d& b0, const Mat3D<double>& B, MassMomentsN<3>* mm) {
  const int D = int(B.cols());
  mm->m += m;
  mm->c0 += m * b0;
  mm->C += m * B;
  mm->e0 += m * B.transpose() * b0;
  mm->G += m * B.transpose() * B;
  mm->S0 += m * b0 * b0.transpose();
  for (int d = 0; d < D; ++d) {
    const Eigen::Vector3d Bd = B.col(d);
    mm->H0.col(d) += m * b0.cross(Bd);
    mm->E[d] += m * b0 * Bd.transpose();
    for (int e = 0; e < D; ++e) {
      mm->F[size_t(d) * D + e] += m * Bd * B.col(e).transpose();
      mm->X[size_t(d) * D + e] += m * Bd.cross(B.col(e));
    }
  }
}

bool MomentsFinite(const MassMomentsN<2>& mm) {
  return std::isfinite(mm.m) && std::isfinite(mm.I0) && mm.c0.allFinite() && mm.C.allFinite() && mm.e0.allFinite() &&
         mm.h0.allFinite() && mm.G.allFinite() && mm.P.allFinite();
}
bool MomentsFinite(const MassMomentsN<3>& mm) {
  bool finite = std::isfinite(mm.m) && mm.c0.allFinite() && mm.C.allFinite() && mm.H0.allFinite() &&
                mm.e0.allFinite() && mm.G.allFinite() && mm.S0.allFinite();
  for (const auto& x : mm.E) finite = finite && x.allFinite();
  for (const auto& x : mm.F) finite = finite && x.allFinite();
  for (const auto& x : mm.X) finite = finite && x.allFinite();
  return finite;
}

}  // namespace

template <int Dim>
BodyModelN<Dim>::BodyModelN(BodyDefN<Dim> def, std::vector<DeformationModeN<Dim>> modes)
    : def_(std::move(def)), modes_(std::move(modes)) {
  const LatticeN<Dim>& lat = def_.lattice;
  const int D = num_modes();
  if (D > kMaxModes)
    throw std::invalid_argument("body '" + def_.name + "' has " + std::to_string(D) + " modes; at most " +
                                std::to_string(kMaxModes) + " are supported");
  for (const DeformationModeN<Dim>& mode : modes_) {
    if (mode.lattice_size != lat.sizes() || int(mode.displacement.size()) != lat.size())
      throw std::invalid_argument((mode.source.empty() ? "" : mode.source + ": ") + "mode '" + mode.name +
                                  "' is defined on a " + SizeText<Dim>(mode.lattice_size) + " lattice but body '" +
                                  def_.name + "' has a " + SizeText<Dim>(lat.sizes()) + " lattice");
  }
  if (def_.masses.size() != def_.mass_positions.size())
    throw std::invalid_argument("body '" + def_.name + "': mass and position counts differ");
  if (def_.masses.empty()) throw std::invalid_argument("body '" + def_.name + "' has no mass points");
  for (double m : def_.masses)
    if (!(m > 0) || !std::isfinite(m)) throw std::invalid_argument("body '" + def_.name + "': masses must be positive");

  rest_control_ = lat.RestPoints();
  const int N = num_points();
  lattice_coords_.resize(N);
  rest_local_.resize(N);
  mode_rows_.assign(size_t(Dim) * D * N, 0.0);

  StartMoments(D, &moments_);
  for (int k = 0; k < N; ++k) {
    // b0_k and B_k from the constant Bernstein (or B-spline) weights of the point
    lattice_coords_[k] = lat.LocalCoords(def_.mass_positions[k]);
    ModeMatrix B;
    LocalBasis(lattice_coords_[k], &rest_local_[k], &B);
    Eigen::Map<Eigen::Matrix<double, Dim, Eigen::Dynamic>>(mode_rows_.data() + Dim * D * k, Dim, D) = B;
    AddPoint(def_.masses[k], rest_local_[k], B, &moments_);
  }
  MassMomentsN<Dim>& mm = moments_;
  if (!MomentsFinite(mm))
    throw std::invalid_argument("body '" + def_.name + "': its masses, positions or mode displacements are so large " +
                                "that the mass moments overflow");
  mm.G_com_factor = mm.G - mm.C.transpose() * mm.C / mm.m;
  mm.G_com_positive = CholeskyInPlace(&mm.G_com_factor);
  if constexpr (Dim == 3) {
    if (mm.G_com_positive) {
      // column j of G_com⁻¹ solves G_com x = e_j; symmetrized, as the exact inverse is
      mm.G_com_inverse.setIdentity(D, D);
      for (int j = 0; j < D; ++j) {
        VecD<double> x = mm.G_com_inverse.col(j);
        CholeskySolveInPlace(mm.G_com_factor, &x);
        mm.G_com_inverse.col(j) = x;
      }
      mm.G_com_inverse = (0.5 * (mm.G_com_inverse + mm.G_com_inverse.transpose())).eval();
      mm.G_com_pivot_lo = std::numeric_limits<double>::infinity();
      mm.G_com_pivot_hi = 0.0;
      CholeskyPivotRange(mm.G_com_factor, &mm.G_com_pivot_lo, &mm.G_com_pivot_hi);
    }
  }
  mode_reach_.assign(size_t(N), 0.0);
  for (int k = 0; k < N; ++k) {
    for (int d = 0; d < D; ++d) mode_reach_[size_t(k)] = std::max(mode_reach_[size_t(k)], mode_matrix(k).col(d).cwiseAbs().sum());
    rest_extent_ = std::max(rest_extent_, rest_local_[k].cwiseAbs().sum());
    max_mode_reach_ = std::max(max_mode_reach_, mode_reach_[size_t(k)]);
  }
  BuildClusters();
  BuildTree();

  const int V = int(def_.mesh.points.size());
  mesh_rest_local_.resize(V);
  mesh_mode_rows_.assign(size_t(Dim) * D * V, 0.0);
  for (int v = 0; v < V; ++v) {
    ModeMatrix B;
    LocalBasis(lat.LocalCoords(def_.mesh.points[v]), &mesh_rest_local_[v], &B);
    Eigen::Map<Eigen::Matrix<double, Dim, Eigen::Dynamic>>(mesh_mode_rows_.data() + Dim * D * v, Dim, D) = B;
  }
}

template <int Dim> void BodyModelN<Dim>::BuildClusters() {
  const int N = num_points(), D = num_modes();
  // a square (cubic) grid of cells over the lattice coordinates, about kPointsPerCluster per cell
  const int cells = std::max(1, int(std::lround(std::pow(double(N) / kPointsPerCluster, 1.0 / Dim))));
  size_t num_cells = 1;
  for (int a = 0; a < Dim; ++a) num_cells *= size_t(cells);
  std::vector<std::vector<int>> members(num_cells);
  for (int k = 0; k < N; ++k) {
    auto cell = [&](double u) { return std::clamp(int(std::floor(u * cells)), 0, cells - 1); };
    size_t index = 0;
    for (int a = 0; a < Dim; ++a) index = index * cells + size_t(cell(lattice_coords_[k][a]));
    members[index].push_back(k);
  }
  clusters_.clear();
  for (std::vector<int>& pts : members) {
    if (pts.empty()) continue;
    // per coordinate, the interval of b0 and of each column of B over the group's points
    auto interval = [&](auto value) {
      Point lo = value(pts[0]), hi = lo;
      for (int k : pts) lo = lo.cwiseMin(value(k)), hi = hi.cwiseMax(value(k));
      return std::make_pair(Point(0.5 * (lo + hi)), Point(0.5 * (hi - lo)));
    };
    PointClusterN<Dim> c;
    c.points = pts;
    std::tie(c.centre0, c.half0) = interval([&](int k) { return rest_local_[k]; });
    c.centre_modes.setZero(Dim, D);
    c.half_modes.setZero(Dim, D);
    for (int d = 0; d < D; ++d) {
      const auto [centre, half] = interval([&](int k) { return Point(mode_matrix(k).col(d)); });
      c.centre_modes.col(d) = centre;
      c.half_modes.col(d) = half;
    }
    clusters_.push_back(std::move(c));
  }
}

namespace {

// Node of the points of ranks [lo, hi) of tree->by_rank (the scan order): its bounds (as the
// clusters'), then its children, split at the group boundary nearest the middle, or at the
// middle inside one group. Splitting the scan order, not space, keeps the leaves in scan
// order, so the scan never sorts what it visits; the groups are cells of the lattice, and
// inside a group, points given in order along the body (a drawing resampled, a grid) make
// tight boxes.
template <int Dim>
void BuildTreeNode(const BodyModelN<Dim>& body, int lo, int hi, const std::vector<int>& group_starts,
                   PointTreeN<Dim>* tree) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  const int D = body.num_modes(), L = tree->width;
  const int node = int(tree->skip.size());
  tree->skip.push_back(0);
  tree->first.push_back(0);
  tree->last.push_back(0);
  tree->bounds.resize(tree->bounds.size() + size_t(tree->stride), 0.0);
  double* centre = tree->bounds.data() + size_t(node) * size_t(tree->stride);
  double* half = centre + L;
  for (int block = 0; block <= D; ++block) {
    auto value = [&](int r) {
      const int k = tree->by_rank[size_t(r)];
      return block == 0 ? body.rest_local(k) : Point(body.mode_matrix(k).col(block - 1));
    };
    Point low = value(lo), high = low;
    for (int r = lo; r < hi; ++r) low = low.cwiseMin(value(r)), high = high.cwiseMax(value(r));
    for (int a = 0; a < Dim; ++a) {
      centre[Dim * block + a] = 0.5 * (low[a] + high[a]);
      half[Dim * block + a] = 0.5 * (high[a] - low[a]);
      if (block > 0) half[L + a] = std::max(half[L + a], std::abs(centre[Dim * block + a]) + half[Dim * block + a]);
    }
  }
  int split = -1;
  if (hi - lo > PointTreeN<Dim>::kLeafPoints) {
    const int middle = lo + (hi - lo) / 2;
    for (int start : group_starts)
      if (start > lo && start < hi && (split < 0 || std::abs(start - middle) < std::abs(split - middle))) split = start;
    const bool inside_group = split < 0;
    if (inside_group) split = middle;
    // Inside a group whose points come in no order along the body, halves of the range are
    // as wide as the whole and every node below would pass where the whole passes: such a
    // node stays a leaf (the group's own test, as before the tree). Across groups, always split.
    auto size = [&](int from, int to) {
      Point low = body.rest_local(tree->by_rank[size_t(from)]), high = low;
      for (int r = from; r < to; ++r)
        low = low.cwiseMin(body.rest_local(tree->by_rank[size_t(r)])), high = high.cwiseMax(body.rest_local(tree->by_rank[size_t(r)]));
      return (high - low).sum();
    };
    if (inside_group && std::max(size(lo, split), size(split, hi)) > 0.75 * size(lo, hi)) split = -1;
  }
  if (split < 0) {
    tree->first[size_t(node)] = int(tree->leaf_ranks.size());
    for (int r = lo; r < hi; ++r) tree->leaf_ranks.push_back(r);
    tree->last[size_t(node)] = int(tree->leaf_ranks.size());
  } else {
    BuildTreeNode(body, lo, split, group_starts, tree);
    BuildTreeNode(body, split, hi, group_starts, tree);
  }
  tree->skip[size_t(node)] = int(tree->skip.size());
}

}  // namespace

template <int Dim> void BodyModelN<Dim>::BuildTree() {
  tree_ = PointTreeN<Dim>();
  if (clusters_.size() <= 1) return;  // small bodies: the scan tests every point
  static std::atomic<std::uint64_t> serials{0};
  tree_.serial = ++serials;
  tree_.width = Dim * (num_modes() + 1);
  tree_.stride = 2 * tree_.width + Dim;
  std::vector<int> group_starts;
  for (const PointClusterN<Dim>& c : clusters_) {
    group_starts.push_back(int(tree_.by_rank.size()));
    tree_.by_rank.insert(tree_.by_rank.end(), c.points.begin(), c.points.end());
  }
  BuildTreeNode(*this, 0, int(tree_.by_rank.size()), group_starts, &tree_);
}

template <int Dim> void BodyModelN<Dim>::LocalBasis(const Point& st, Point* b0, ModeMatrix* B) const {
  const LatticeN<Dim>& lat = def_.lattice;
  const std::vector<double> w = lat.Weights(st);
  b0->setZero();
  B->setZero(Dim, num_modes());
  for (int c = 0; c < lat.size(); ++c) {
    if (w[c] == 0.0) continue;
    *b0 += w[c] * rest_control_[c];
    for (int d = 0; d < num_modes(); ++d) B->col(d) += w[c] * modes_[d].displacement[c];
  }
}

template class BodyModelN<2>;
template class BodyModelN<3>;

}  // namespace wobble
