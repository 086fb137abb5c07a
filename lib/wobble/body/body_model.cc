#include "wobble/body/body_model.h"

#include "wobble/core/cholesky.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <stdexcept>

namespace wobble {

BodyModel::BodyModel(BodyDef def, std::vector<DeformationMode> modes) : def_(std::move(def)), modes_(std::move(modes)) {
  const Lattice& lat = def_.lattice;
  const int D = num_modes();
  if (D > kMaxModes)
    throw std::invalid_argument("body '" + def_.name + "' has " + std::to_string(D) + " modes; at most " +
                                std::to_string(kMaxModes) + " are supported");
  for (const DeformationMode& mode : modes_) {
    if (mode.num_s != lat.num_s() || mode.num_t != lat.num_t() || int(mode.displacement.size()) != lat.size())
      throw std::invalid_argument((mode.source.empty() ? "" : mode.source + ": ") + "mode '" + mode.name + "' is defined on a " + std::to_string(mode.num_s) + "x" +
                                  std::to_string(mode.num_t) + " lattice but body '" + def_.name + "' has a " +
                                  std::to_string(lat.num_s()) + "x" + std::to_string(lat.num_t()) + " lattice");
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
  mode_rows_.assign(size_t(2) * D * N, 0.0);

  MassMoments& mm = moments_;
  mm.C.setZero(2, D);
  mm.e0.setZero(D);
  mm.h0.setZero(D);
  mm.G.setZero(D, D);
  mm.P.setZero(D, D);
  for (int k = 0; k < N; ++k) {
    // b0_k and B_k from the constant Bernstein (or B-spline) weights of the point
    lattice_coords_[k] = lat.LocalCoords(def_.mass_positions[k]);
    Mat2D<double> B;
    LocalBasis(lattice_coords_[k], &rest_local_[k], &B);
    Eigen::Map<Eigen::Matrix<double, 2, Eigen::Dynamic>>(mode_rows_.data() + 2 * D * k, 2, D) = B;

    // accumulate the moments
    const double m = def_.masses[k];
    const Eigen::Vector2d& b0 = rest_local_[k];
    const Eigen::Vector2d Sb0(-b0.y(), b0.x());
    Mat2D<double> SB(2, D);
    SB.row(0) = -B.row(1);
    SB.row(1) = B.row(0);
    mm.m += m;
    mm.c0 += m * b0;
    mm.I0 += m * b0.squaredNorm();
    mm.C += m * B;
    mm.e0 += m * B.transpose() * b0;
    mm.h0 += m * B.transpose() * Sb0;
    mm.G += m * B.transpose() * B;
    mm.P += m * B.transpose() * SB;
  }
  mm.G_com_factor = mm.G - mm.C.transpose() * mm.C / mm.m;
  mm.G_com_positive = CholeskyInPlace(&mm.G_com_factor);
  BuildClusters();
}

void BodyModel::BuildClusters() {
  const int N = num_points(), D = num_modes();
  // a square grid of cells over the lattice coordinates, about kPointsPerCluster per cell
  const int cells = std::max(1, int(std::lround(std::sqrt(double(N) / kPointsPerCluster))));
  std::vector<std::vector<int>> members(size_t(cells) * cells);
  for (int k = 0; k < N; ++k) {
    auto cell = [&](double u) { return std::clamp(int(std::floor(u * cells)), 0, cells - 1); };
    members[size_t(cell(lattice_coords_[k].x())) * cells + cell(lattice_coords_[k].y())].push_back(k);
  }
  clusters_.clear();
  for (std::vector<int>& pts : members) {
    if (pts.empty()) continue;
    // per coordinate, the interval of b0 and of each column of B over the group's points
    auto interval = [&](auto value) {
      Eigen::Vector2d lo = value(pts[0]), hi = lo;
      for (int k : pts) lo = lo.cwiseMin(value(k)), hi = hi.cwiseMax(value(k));
      return std::make_pair(Eigen::Vector2d(0.5 * (lo + hi)), Eigen::Vector2d(0.5 * (hi - lo)));
    };
    PointCluster c;
    c.points = pts;
    std::tie(c.centre0, c.half0) = interval([&](int k) { return rest_local_[k]; });
    c.centre_modes.setZero(2, D);
    c.half_modes.setZero(2, D);
    for (int d = 0; d < D; ++d) {
      const auto [centre, half] = interval([&](int k) { return Eigen::Vector2d(mode_matrix(k).col(d)); });
      c.centre_modes.col(d) = centre;
      c.half_modes.col(d) = half;
    }
    clusters_.push_back(std::move(c));
  }
}

void BodyModel::LocalBasis(const Eigen::Vector2d& st, Eigen::Vector2d* b0, Mat2D<double>* B) const {
  const Lattice& lat = def_.lattice;
  const std::vector<double> w = lat.Weights(st);
  b0->setZero();
  B->setZero(2, num_modes());
  for (int c = 0; c < lat.size(); ++c) {
    if (w[c] == 0.0) continue;
    *b0 += w[c] * rest_control_[c];
    for (int d = 0; d < num_modes(); ++d) B->col(d) += w[c] * modes_[d].displacement[c];
  }
}

}  // namespace wobble
