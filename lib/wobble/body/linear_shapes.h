// Shapes for linear-deformation bodies (Witkin & Welch 1990, the figures' blocks, pyramid
// and hook): their mass points and their drawing, both in undeformed coordinates u. A drawing
// is never simulated; it is carried by the deformation x = R p(u) like the mass points (the
// pictures sample it finer than the mass points, so a quadratic body is seen to bend).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "wobble/body/linear_body.h"

namespace wobble {

// Lines and a surface in undeformed coordinates (2D drawings have polylines only).
struct LinearDrawing {
  struct Polyline {
    std::vector<Eigen::VectorXd> points;
    bool closed = false;
  };
  std::vector<Polyline> polylines;
  std::vector<Eigen::VectorXd> vertices;     // of the surface
  std::vector<std::array<int, 3>> triangles;  // indices into vertices
  int dim() const;                            // 0 when empty
};

// The edges (2D: the outline) of the box [-half, half], each cut into `pieces` segments, and in
// 3D its six faces as a pieces × pieces grid of triangle pairs. pieces >= 1.
LinearDrawing MakeBoxDrawing(const Eigen::VectorXd& half_extents, int pieces);

// A pyramid standing on its base at y = 0 with its apex at (0, height[, 0]): 2D a triangle with
// base from −half_width to half_width along x; 3D a square base [−w, w] in x and z.
LinearDrawing MakePyramidDrawing(int dim, double half_width, double height, int pieces);

// The pyramid's mass points: `levels` (>= 2) layers from the base to below the apex, each a grid
// of `per_side` (>= 2) points per axis across the layer's section, plus one point at the apex;
// equal masses summing to `mass`. Throws std::invalid_argument on bad sizes.
LinearBodyDef MakePyramidBody(const std::string& name, int dim, LinearOrder order, double half_width, double height,
                              int levels, int per_side, double mass);

}  // namespace wobble
