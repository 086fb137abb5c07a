// The characters' layers of an EXR frame (pipelines/exr_frame.h), against closed forms: the
// pixel centres a triangle, a wide segment and a dot cover; motion vectors of an affine motion
// exact at every covered pixel, in a parallel view and (a plane seen in perspective, checked by
// casting the pixel's ray) in a perspective one; the nearer surface winning; no motion without
// a next frame or when a drawing's vertex count changes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "pipelines/exr_frame.h"

namespace wobble::pipelines {
namespace {

// A parallel view: pixels are world units, w = 1, depth z as given.
ScreenGeometry Flat(const std::vector<Eigen::Vector3d>& v) {
  ScreenGeometry g;
  g.vertices = v;
  g.w.assign(v.size(), 1.0);
  g.groups = {int(v.size())};
  return g;
}

double At(const std::vector<float>& layer, int width, int height, int x, int y_up) {
  return layer[size_t(height - 1 - y_up) * width + x];  // layers have row 0 at the top
}

TEST(CharacterRaster, TriangleCoversThePixelCentresInsideIt) {
  // (0, 0), (10, 0), (0, 10): centre (i + ½, j + ½) is inside when i + j + 1 <= 10
  ScreenGeometry g = Flat({{0, 0, 0.5}, {10, 0, 0.5}, {0, 10, 0.5}});
  g.triangles = {{0, 1, 2}};
  const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, ScreenGeometry()), 16, 12);
  int covered = 0;
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 16; ++x) {
      const bool inside = x + y + 1 <= 10;
      EXPECT_EQ(At(c.alpha, 16, 12, x, y), inside ? 1.0 : 0.0) << x << "," << y;
      EXPECT_EQ(At(c.forward_u, 16, 12, x, y), 0.0);  // no next frame: no motion
      covered += inside;
    }
  EXPECT_EQ(covered, 55);
}

// Blender's Vector pass needs the motion to the previous frame too: with a previous position
// that is another affine map of this one, both motions are exact at every covered pixel, and
// without a previous frame the motion back is zero.
TEST(CharacterRaster, MotionToThePreviousFrameIsExactToo) {
  const std::vector<Eigen::Vector3d> now = {{3, 2, 0.5}, {37, 5, 0.5}, {33, 27, 0.5}, {6, 24, 0.5}};
  auto mapped = [&](const Eigen::Matrix2d& A, const Eigen::Vector2d& b) {
    std::vector<Eigen::Vector3d> out;
    for (const Eigen::Vector3d& v : now) {
      const Eigen::Vector2d p = A * v.head<2>() + b;
      out.emplace_back(p.x(), p.y(), 0.5);
    }
    return out;
  };
  Eigen::Matrix2d A_next, A_before;
  A_next << 1.05, 0.1, -0.05, 0.95;
  A_before << 0.9, -0.2, 0.15, 1.1;
  const Eigen::Vector2d b_next(2.0, 1.5), b_before(-3.25, 4.0);
  ScreenGeometry g = Flat(now);
  g.triangles = {{0, 1, 2}, {0, 2, 3}};
  const std::vector<Eigen::Vector3d> before = NextPixels(g, Flat(mapped(A_before, b_before)));
  const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, Flat(mapped(A_next, b_next))), 40, 30, &before);
  const CharacterLayers alone = RasterizeCharacters(g, NextPixels(g, Flat(mapped(A_next, b_next))), 40, 30);
  int covered = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      if (At(c.alpha, 40, 30, x, y) == 0) continue;
      const Eigen::Vector2d p(x + 0.5, y + 0.5), forward = A_next * p + b_next - p, back = A_before * p + b_before - p;
      EXPECT_NEAR(At(c.forward_u, 40, 30, x, y), forward.x(), 1e-4) << x << "," << y;
      EXPECT_NEAR(At(c.forward_v, 40, 30, x, y), forward.y(), 1e-4) << x << "," << y;
      EXPECT_NEAR(At(c.backward_u, 40, 30, x, y), back.x(), 1e-4) << x << "," << y;
      EXPECT_NEAR(At(c.backward_v, 40, 30, x, y), back.y(), 1e-4) << x << "," << y;
      ++covered;
    }
  EXPECT_GT(covered, 600);
  // without a previous frame the backward layers are not made at all (they cost a raster pass)
  EXPECT_TRUE(alone.backward_u.empty());
  EXPECT_TRUE(alone.backward_v.empty());
  EXPECT_EQ(alone.forward_u, c.forward_u);
}

TEST(CharacterRaster, AffineMotionIsExactAtEveryCoveredPixel) {
  // a quad of two triangles, its next position an affine map of this one: motion A p + b − p
  const std::vector<Eigen::Vector3d> now = {{3, 2, 0.5}, {37, 5, 0.5}, {33, 27, 0.5}, {6, 24, 0.5}};
  Eigen::Matrix2d A;
  A << std::cos(0.2), -std::sin(0.2), std::sin(0.2), std::cos(0.2);
  A *= 1.1;
  const Eigen::Vector2d b(4.5, -2.25);
  std::vector<Eigen::Vector3d> moved;
  for (const Eigen::Vector3d& v : now) {
    const Eigen::Vector2d p = A * v.head<2>() + b;
    moved.emplace_back(p.x(), p.y(), 0.5);
  }
  ScreenGeometry g = Flat(now);
  g.triangles = {{0, 1, 2}, {0, 2, 3}};
  const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, Flat(moved)), 40, 30);
  int covered = 0;
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      if (At(c.alpha, 40, 30, x, y) == 0) continue;
      const Eigen::Vector2d p(x + 0.5, y + 0.5), m = A * p + b - p;
      EXPECT_NEAR(At(c.forward_u, 40, 30, x, y), m.x(), 1e-4) << x << "," << y;
      EXPECT_NEAR(At(c.forward_v, 40, 30, x, y), m.y(), 1e-4) << x << "," << y;
      ++covered;
    }
  EXPECT_GT(covered, 600);  // the quad's area is about 690 pixels
}

TEST(CharacterRaster, WideSegmentAndDotCoverTheirRectangles) {
  // a segment (2, 5.5)-(12, 5.5) 3 pixels wide: rows with |y + ½ − 5.5| <= 1.5, columns with
  // 2 <= x + ½ <= 12; a dot of side 4 at (20, 20): centres within 2 of it on both axes
  ScreenGeometry g = Flat({{2, 5.5, 0.5}, {12, 5.5, 0.5}, {20, 20, 0.5}});
  g.segments = {{0, 1, 3.0}};
  g.dots = {{2, 4.0}};
  ScreenGeometry next = Flat({{4, 6.5, 0.5}, {14, 6.5, 0.5}, {19, 23, 0.5}});
  const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, next), 32, 32);
  int covered = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const bool on_line = y >= 4 && y <= 6 && x >= 2 && x <= 11;
      const bool on_dot = x >= 18 && x <= 21 && y >= 18 && y <= 21;
      ASSERT_EQ(At(c.alpha, 32, 32, x, y), on_line || on_dot ? 1.0 : 0.0) << x << "," << y;
      covered += on_line || on_dot;
      if (on_line) {  // every pixel of the width moves with the line: (2, 1)
        EXPECT_NEAR(At(c.forward_u, 32, 32, x, y), 2.0, 1e-6);
        EXPECT_NEAR(At(c.forward_v, 32, 32, x, y), 1.0, 1e-6);
      }
      if (on_dot) {
        EXPECT_NEAR(At(c.forward_u, 32, 32, x, y), -1.0, 1e-6);
        EXPECT_NEAR(At(c.forward_v, 32, 32, x, y), 3.0, 1e-6);
      }
    }
  EXPECT_EQ(covered, 30 + 16);
}

TEST(CharacterRaster, TheNearerSurfaceWinsWhateverTheOrder) {
  // two overlapping squares; the one at depth 0.3 covers the one at 0.6 where they overlap
  ScreenGeometry g = Flat({{0, 0, 0.6}, {10, 0, 0.6}, {10, 10, 0.6}, {0, 10, 0.6},
                           {5, 5, 0.3}, {15, 5, 0.3}, {15, 15, 0.3}, {5, 15, 0.3}});
  ScreenGeometry next = g;
  for (int i = 0; i < 4; ++i) next.vertices[size_t(i)].x() += 1.0;      // the far square moves right
  for (int i = 4; i < 8; ++i) next.vertices[size_t(i)].y() += 2.0;      // the near one up
  for (bool near_first : {false, true}) {
    g.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    if (near_first) std::swap(g.triangles[0], g.triangles[2]), std::swap(g.triangles[1], g.triangles[3]);
    const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, next), 20, 20);
    EXPECT_NEAR(At(c.forward_u, 20, 20, 7, 7), 0.0, 1e-9);  // overlap: the near square
    EXPECT_NEAR(At(c.forward_v, 20, 20, 7, 7), 2.0, 1e-9);
    EXPECT_NEAR(At(c.forward_u, 20, 20, 2, 2), 1.0, 1e-9);  // the far square alone
    EXPECT_NEAR(At(c.forward_v, 20, 20, 2, 2), 0.0, 1e-9);
  }
}

TEST(CharacterRaster, PerspectiveMotionOfATiltedPlaneMatchesTheRayCast) {
  // a pinhole camera at the origin looking down −z, focal length f pixels, image centre c:
  // pixel = c + f (X, Y) / (−Z), w = −Z. A tilted triangle moves by a rotation about y and a
  // translation; at each covered pixel, the ray through its centre meets the triangle's plane
  // at the point drawn there, whose image after the motion is where the pixel goes.
  const double f = 40, cx = 32, cy = 24;
  auto project = [&](const Eigen::Vector3d& X, Eigen::Vector3d* pixel, double* w) {
    *w = -X.z();
    *pixel = Eigen::Vector3d(cx + f * X.x() / *w, cy + f * X.y() / *w, 0.5);
  };
  const Eigen::Vector3d P[3] = {{-1.5, -1.0, -3.0}, {1.8, -0.6, -6.0}, {-0.2, 1.4, -4.0}};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d T(0.2, -0.1, 0.3);
  ScreenGeometry g, next;
  for (const Eigen::Vector3d& X : P) {
    Eigen::Vector3d p;
    double w;
    project(X, &p, &w);
    g.vertices.push_back(p);
    g.w.push_back(w);
    project(R * X + T, &p, &w);
    next.vertices.push_back(p);
    next.w.push_back(w);
  }
  g.groups = next.groups = {3};
  g.triangles = {{0, 1, 2}};
  const CharacterLayers c = RasterizeCharacters(g, NextPixels(g, next), 64, 48);
  const Eigen::Vector3d n = (P[1] - P[0]).cross(P[2] - P[0]);
  int covered = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      if (At(c.alpha, 64, 48, x, y) == 0) continue;
      const Eigen::Vector3d ray((x + 0.5 - cx) / f, (y + 0.5 - cy) / f, -1.0);
      const Eigen::Vector3d X = ray * (n.dot(P[0]) / n.dot(ray));
      Eigen::Vector3d there;
      double w;
      project(R * X + T, &there, &w);
      EXPECT_NEAR(At(c.forward_u, 64, 48, x, y), there.x() - (x + 0.5), 1e-4) << x << "," << y;
      EXPECT_NEAR(At(c.forward_v, 64, 48, x, y), there.y() - (y + 0.5), 1e-4) << x << "," << y;
      ++covered;
    }
  EXPECT_GT(covered, 150);
}

TEST(CharacterRaster, NoMotionWhereAGroupChangedOrNothingFollows) {
  ScreenGeometry g = Flat({{1, 1, 0.5}, {2, 1, 0.5}, {5, 5, 0.5}});
  g.groups = {2, 1};
  ScreenGeometry next = Flat({{3, 1, 0.5}, {4, 1, 0.5}, {9, 9, 0.5}, {9, 8, 0.5}});
  next.groups = {2, 2};  // the second drawing now has two vertices: nothing ties them
  const std::vector<Eigen::Vector3d> h = NextPixels(g, next);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0], Eigen::Vector3d(3, 1, 1));
  EXPECT_EQ(h[1], Eigen::Vector3d(4, 1, 1));
  EXPECT_EQ(h[2], Eigen::Vector3d(5, 5, 1));  // where it is now
  EXPECT_THROW(RasterizeCharacters(g, {}, 8, 8), std::invalid_argument);
}

}  // namespace
}  // namespace wobble::pipelines
