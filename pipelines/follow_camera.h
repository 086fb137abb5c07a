// The follow camera of renders (issue 19): for each drawn moment, the box to frame so that
// the body stays in view at one scale for the whole run, the ground under it shows when it can,
// and the camera moves smoothly. Plain geometry, no VTK: the render driver feeds it the body's
// box and the ground's height under it at every frame and filmstrip panel.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace wobble::pipelines {

// The body's box at one moment and the ground's surface height under its centre, if any (2D:
// the line or terrain under x; 3D: the plane or heightfield under x, z).
template <int Dim> struct FollowMomentN {
  double t = 0;
  Eigen::AlignedBox<double, Dim> body;  // the body's box now
  std::optional<double> ground_height;
};
using FollowMoment = FollowMomentN<2>;

struct FollowOptions {
  double aspect = 4.0 / 3.0;  // width / height of the pictures
  double zoom = 1.8;          // the view is this many times the body's largest half-extent
  double smoothing_s = 0.15;  // the camera path's smoothing, seconds (σ of its Gaussian weights)
};

// One box per moment (same order), all of one size: zoom times the body's largest
// half-extent, as the view's half-height. 2D: a box of the picture's aspect for the parallel
// camera; 3D: a cube for the perspective camera to frame (SceneView::FrameBox3d; the aspect is
// not used). Centred on the body in x (and z); in y the ground sits a fifth up from the bottom
// edge unless the body would leave the view (then the body is kept in: 7.5 % above the bottom
// edge, and out of the top fifth, where the overlay's text is). Centres are smoothed by a
// Gaussian-weighted local linear fit in time, so a body moving at constant velocity is
// followed exactly, to the first and last moment, while jumps (the ground under the body at a
// cliff's edge) are eased over ~4σ.
template <int Dim>
std::vector<Eigen::AlignedBox<double, Dim>> FollowBoxes(const std::vector<FollowMomentN<Dim>>& moments,
                                                        const FollowOptions& options);

}  // namespace wobble::pipelines
