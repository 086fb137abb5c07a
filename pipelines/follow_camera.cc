#include "pipelines/follow_camera.h"

#include <algorithm>
#include <cmath>

namespace wobble::pipelines {

namespace {

// The value at t_i of the line fitted to (t_j, y_j) with weights exp(−(t_j − t_i)² / 2σ²).
double LocalLinearFit(const std::vector<double>& t, const std::vector<double>& y, size_t i, double sigma) {
  double s0 = 0, s1 = 0, s2 = 0, sy = 0, sty = 0;
  for (size_t j = 0; j < t.size(); ++j) {
    const double d = t[j] - t[i];
    if (std::abs(d) > 4 * sigma) continue;
    const double w = std::exp(-0.5 * d * d / (sigma * sigma));
    s0 += w;
    s1 += w * d;
    s2 += w * d * d;
    sy += w * y[j];
    sty += w * d * y[j];
  }
  const double det = s0 * s2 - s1 * s1;
  // one moment in the window (or all at one time): its weighted mean
  if (!(det > 1e-12 * s0 * s0 * sigma * sigma)) return sy / s0;
  return (s2 * sy - s1 * sty) / det;  // the intercept at d = 0
}

// The view's centre height for a body spanning [body_min_y, body_max_y] in a view half_h
// high: the ground a fifth up the picture, but the body in view wins over the ground (7.5 %
// inside the bottom edge, and below the top fifth, where the overlay's text lines are).
double PlacedCentreY(double body_min_y, double body_max_y, const std::optional<double>& ground_height, double half_h) {
  const double centre = 0.5 * (body_min_y + body_max_y);
  const double y = ground_height ? *ground_height + 0.6 * half_h : centre;
  const double lo = body_max_y - 0.6 * half_h, hi = body_min_y + 0.85 * half_h;
  return lo <= hi ? std::clamp(y, lo, hi) : centre;
}

}  // namespace

template <int Dim>
std::vector<Eigen::AlignedBox<double, Dim>> FollowBoxes(const std::vector<FollowMomentN<Dim>>& moments,
                                                        const FollowOptions& options) {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  std::vector<Eigen::AlignedBox<double, Dim>> boxes;
  if (moments.empty()) return boxes;
  // the view's half-extents per unit of half-height: the picture's in 2D, a cube in 3D (the
  // perspective camera fits the whole cube)
  Vec shape = Vec::Ones();
  if constexpr (Dim == 2) shape.x() = options.aspect;
  double reach = 1e-9;  // the largest half-extent of the body, as a half-height of the view
  for (const FollowMomentN<Dim>& m : moments) reach = std::max(reach, (0.5 * m.body.sizes()).cwiseQuotient(shape).maxCoeff());
  const Vec half = options.zoom * reach * shape;
  std::vector<double> t;
  std::vector<std::vector<double>> centre(Dim);  // per axis
  for (const FollowMomentN<Dim>& m : moments) {
    t.push_back(m.t);
    for (int a = 0; a < Dim; ++a)
      centre[size_t(a)].push_back(a == 1 ? PlacedCentreY(m.body.min().y(), m.body.max().y(), m.ground_height, half.y())
                                         : m.body.center()[a]);
  }
  const double sigma = std::max(options.smoothing_s, 1e-9);
  for (size_t i = 0; i < moments.size(); ++i) {
    Vec c;
    for (int a = 0; a < Dim; ++a) c[a] = LocalLinearFit(t, centre[size_t(a)], i, sigma);
    boxes.emplace_back(c - half, c + half);
  }
  return boxes;
}

template std::vector<Eigen::AlignedBox2d> FollowBoxes<2>(const std::vector<FollowMomentN<2>>&, const FollowOptions&);
template std::vector<Eigen::AlignedBox3d> FollowBoxes<3>(const std::vector<FollowMomentN<3>>&, const FollowOptions&);

}  // namespace wobble::pipelines
