// The follow camera of renders (issue 19): for each drawn moment, the box to frame so that
// the body stays in view at one scale for the whole run, the ground under it shows when it can,
// and the camera moves smoothly. Plain geometry, no VTK: the render driver feeds it the body's
// box and the ground's height under it at every frame and filmstrip panel.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace wobble::pipelines {

struct FollowMoment {
  double t = 0;
  Eigen::AlignedBox2d body;             // the body's box now
  std::optional<double> ground_height;  // the ground's surface under the body's centre, if any
};

struct FollowOptions {
  double aspect = 4.0 / 3.0;  // width / height of the pictures
  double zoom = 1.8;          // the view is this many times the body's largest half-extent
  double smoothing_s = 0.15;  // the camera path's smoothing, seconds (σ of its Gaussian weights)
};

// One box per moment (same order), all of one size: centred on the body in x; in y the ground
// sits a fifth up from the bottom edge unless the body would leave the view (then the body is
// kept in: 7.5 % above the bottom edge, and out of the top fifth, where the overlay's text is). Centres are smoothed by a Gaussian-weighted local linear fit
// in time, so a body moving at constant velocity is followed exactly, to the first and last
// moment, while jumps (the ground under the body at a cliff's edge) are eased over ~4σ.
std::vector<Eigen::AlignedBox2d> FollowBoxes(const std::vector<FollowMoment>& moments, const FollowOptions& options);

// 3D: the body's box and the ground's height under its centre (plane or heightfield).
struct FollowMoment3 {
  double t = 0;
  Eigen::AlignedBox3d body;
  std::optional<double> ground_height;
};
// One cube per moment, all of one size (zoom times the body's largest half-extent, as a half
// side), for the perspective camera to frame (SceneView::FrameBox3d): centred on the body in x
// and z, and in y placed as the 2D boxes are, so the ground under the body shows in the lower
// part of the picture; smoothed in time as in 2D.
std::vector<Eigen::AlignedBox3d> FollowBoxes3(const std::vector<FollowMoment3>& moments, const FollowOptions& options);

}  // namespace wobble::pipelines
