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

std::vector<Eigen::AlignedBox2d> FollowBoxes(const std::vector<FollowMoment>& moments, const FollowOptions& options) {
  std::vector<Eigen::AlignedBox2d> boxes;
  if (moments.empty()) return boxes;
  double reach = 1e-9;  // the largest half-extent of the body, as a half-height of the view
  for (const FollowMoment& m : moments) {
    const Eigen::Vector2d half = 0.5 * m.body.sizes();
    reach = std::max({reach, half.y(), half.x() / options.aspect});
  }
  const double half_h = options.zoom * reach, half_w = half_h * options.aspect;
  std::vector<double> t, cx, cy;
  for (const FollowMoment& m : moments) {
    t.push_back(m.t);
    cx.push_back(m.body.center().x());
    cy.push_back(PlacedCentreY(m.body.min().y(), m.body.max().y(), m.ground_height, half_h));
  }
  const double sigma = std::max(options.smoothing_s, 1e-9);
  for (size_t i = 0; i < moments.size(); ++i) {
    const Eigen::Vector2d c(LocalLinearFit(t, cx, i, sigma), LocalLinearFit(t, cy, i, sigma));
    boxes.emplace_back(c - Eigen::Vector2d(half_w, half_h), c + Eigen::Vector2d(half_w, half_h));
  }
  return boxes;
}

std::vector<Eigen::AlignedBox3d> FollowBoxes3(const std::vector<FollowMoment3>& moments, const FollowOptions& options) {
  std::vector<Eigen::AlignedBox3d> boxes;
  if (moments.empty()) return boxes;
  double reach = 1e-9;
  for (const FollowMoment3& m : moments) reach = std::max(reach, 0.5 * m.body.sizes().maxCoeff());
  const double half = options.zoom * reach;
  std::vector<double> t, cx, cy, cz;
  for (const FollowMoment3& m : moments) {
    t.push_back(m.t);
    cx.push_back(m.body.center().x());
    cy.push_back(PlacedCentreY(m.body.min().y(), m.body.max().y(), m.ground_height, half));
    cz.push_back(m.body.center().z());
  }
  const double sigma = std::max(options.smoothing_s, 1e-9);
  for (size_t i = 0; i < moments.size(); ++i) {
    const Eigen::Vector3d c(LocalLinearFit(t, cx, i, sigma), LocalLinearFit(t, cy, i, sigma), LocalLinearFit(t, cz, i, sigma));
    boxes.emplace_back(c - Eigen::Vector3d::Constant(half), c + Eigen::Vector3d::Constant(half));
  }
  return boxes;
}

}  // namespace wobble::pipelines
