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
//
// Each cell (both its triangles) may have its own penalty constants, as a 2D terrain's
// segments do (SurfaceOverrides: K_d, C_dam, FR_dam, tan θ; unset ones are the ground's): an
// icy patch, a soft bank. The level continuation has the ground's.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "wobble/dynamics/terrain.h"

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

  // This field with the constants set in `overrides` (those not NaN) on every cell whose
  // centre lies in the box [lo, hi] of (x, z). Throws InputError when a constant is negative or
  // not finite, or when no cell's centre is in the box.
  std::shared_ptr<const Heightfield> WithRegion(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                                                const SurfaceOverrides& overrides) const;
  // Cell (i, j)'s constants (all NaN unless set), i < nx − 1, j < nz − 1; face f's, null when
  // it has none of its own (no cell has, or f is the level continuation).
  int num_cells() const { return (nx_ - 1) * (nz_ - 1); }
  const SurfaceOverrides& CellOverrides(int cell) const;
  const SurfaceOverrides* FaceOverrides(int f) const {
    return cells_.empty() || f >= outside_face() ? nullptr : &cells_[size_t(f / 2)];
  }

  bool operator==(const Heightfield& o) const {
    return origin_ == o.origin_ && spacing_ == o.spacing_ && nx_ == o.nx_ && nz_ == o.nz_ && heights_ == o.heights_ &&
           CellsEqual(o);
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
  bool CellsEqual(const Heightfield& o) const;

  Eigen::Vector2d origin_, spacing_;
  int nx_ = 0, nz_ = 0;
  std::vector<double> heights_;
  std::vector<Eigen::Vector3d> normals_, points_;  // per triangle
  std::vector<std::array<int, 3>> valleys_;         // per triangle: Across(), −1 unless concave
  double max_height_ = 0;
  std::vector<SurfaceOverrides> cells_;  // per cell, i + (nx − 1) j; empty: none set
};

}  // namespace wobble
