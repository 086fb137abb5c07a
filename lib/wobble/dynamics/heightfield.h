// Heightfield: the 3D ground as a surface y = h(x, z) over a regular grid (issue 19), the solid
// below it, felt with the penalty ground of §4.9 (Eq. 4.24/4.25) face by face.
//
// Heights are given at the grid's nodes (x0 + i dx, z0 + j dz), i < nx, j < nz; each cell is
// split along its diagonal from node (i, j) to (i + 1, j + 1) into two flat triangles, so the
// surface is piecewise planar and exact where the data is (a plane given as a grid is that
// plane). Beyond the grid the surface continues level at the height of the nearest edge node
// (the 2D Terrain's level continuation).
//
// Which faces a point below the surface feels (the 2D Terrain's rules carried to triangles):
//   - the triangle under it (straight down), when the point is behind that triangle's plane;
//   - each triangle across an edge of that one where the two meet in a valley (a concave
//     edge), when the point is behind its plane too: a point in a crease feels both faces;
//   - never a face across a convex edge (a ridge, a cliff's top), so a point that passes the
//     edge of a drop leaves the top face at once: no sticking, no tunnelling.
// Outside the grid a point feels the level continuation only.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

namespace wobble {

class Heightfield {
 public:
  // Throws InputError unless nx, nz >= 2, spacing > 0, every number finite (|.| <= 1e15) and
  // heights has nx * nz entries, row by row: heights[i + nx * j] is node (i, j).
  static std::shared_ptr<const Heightfield> Make(const Eigen::Vector2d& origin, const Eigen::Vector2d& spacing,
                                                 int nx, int nz, std::vector<double> heights);

  const Eigen::Vector2d& origin() const { return origin_; }    // (x0, z0)
  const Eigen::Vector2d& spacing() const { return spacing_; }  // (dx, dz)
  int nx() const { return nx_; }
  int nz() const { return nz_; }
  const std::vector<double>& heights() const { return heights_; }
  double Node(int i, int j) const { return heights_[size_t(i) + size_t(nx_) * size_t(j)]; }
  double max_height() const { return max_height_; }

  // Faces: two triangles per cell, 2 (i + (nx − 1) j) and the one after; then the level
  // continuation outside the grid (num_faces() − 1).
  int num_faces() const { return 2 * (nx_ - 1) * (nz_ - 1) + 1; }
  int outside_face() const { return num_faces() - 1; }

  // The surface height over (x, z).
  double HeightAt(double x, double z) const;
  // The plane of face f as a point on it and its unit normal (up, out of the solid); for the
  // level continuation, the level plane through the edge node nearest (x, z).
  void FacePlane(int f, const Eigen::Vector3d& x, Eigen::Vector3d* point, Eigen::Vector3d* normal) const;
  // The faces point x feels (rules above), in increasing order; appends to *out.
  void FacesFelt(const Eigen::Vector3d& x, std::vector<int>* out) const;

  bool operator==(const Heightfield& o) const {
    return origin_ == o.origin_ && spacing_ == o.spacing_ && nx_ == o.nx_ && nz_ == o.nz_ && heights_ == o.heights_;
  }

 private:
  // The cell over (x, z) (inside the grid) and which of its triangles: 0 below the diagonal
  // (u > w in the cell's unit coordinates), 1 above.
  int TriangleUnder(double x, double z) const;
  // Whether faces a and b (sharing an edge) meet in a valley.
  bool Concave(int a, int b) const;
  // The triangles across a's three edges (diagonal, then the two cell edges), −1 where a's edge
  // is the grid's.
  std::array<int, 3> Across(int a) const;
  double Behind(int f, const Eigen::Vector3d& x) const;  // signed height above f's plane

  Eigen::Vector2d origin_, spacing_;
  int nx_ = 0, nz_ = 0;
  std::vector<double> heights_;
  std::vector<Eigen::Vector3d> normals_, points_;  // per triangle
  std::vector<std::array<int, 3>> valleys_;         // per triangle: Across(), −1 unless concave
  double max_height_ = 0;
};

}  // namespace wobble
