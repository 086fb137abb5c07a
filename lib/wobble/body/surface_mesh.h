// A user's triangle mesh as a 3D character's body (issue 15): the surface that is drawn and
// exported (every vertex moved by the FFD), and what the lattice and the mass points are made
// from when the object file does not give them.
//
// The mesh is read by VTK's readers in the app (pipelines/mesh_io.h); lib only sees points and
// triangles, so it stays free of VTK. Everything here is deterministic: the same mesh and
// counts give the same lattice and mass points on every machine.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "wobble/body/lattice.h"

namespace wobble {

// Triangles over points; in the body frame.
template <int Dim> struct TriangleMeshN {
  std::vector<Eigen::Matrix<double, Dim, 1>> points;
  std::vector<std::array<int, 3>> triangles;
  bool empty() const { return triangles.empty(); }
};
using SurfaceMesh = TriangleMeshN<3>;

// What a mesh may hold (a character's drawing, not a film set): more is refused by name.
constexpr int kMaxMeshPoints = 2'000'000;
constexpr int kMaxMeshTriangles = 4'000'000;
// Mass points sampled from a mesh (the step does not care, the load and the contact scan do).
constexpr int kMaxSampledPoints = 200'000;

// Throws InputError naming the problem: no triangles, too many points or triangles, a
// point that is not finite, or a triangle whose index is out of range.
void CheckSurfaceMesh(const SurfaceMesh& mesh);

double SurfaceArea(const SurfaceMesh& mesh);

// The volume the surface encloses, |Σ det[a b c]| / 6 over the triangles (divergence
// theorem); exact for a closed, consistently oriented surface.
double EnclosedVolume(const SurfaceMesh& mesh);

// The generalized winding number of the surface about p (Jacobson et al. 2013): the sum of
// the triangles' signed solid angles (Van Oosterom & Strackee 1983) over 4π. 1 inside a closed
// surface oriented outwards (−1 inwards), 0 outside, and about ±1/2 on a hole's edge;
// overlapping closed parts (a table made of boxes) add up, so "inside" is |winding| ≥ 1/2.
double WindingNumber(const SurfaceMesh& mesh, const Eigen::Vector3d& p);

// The lattice around the mesh: its bounding box, grown by `margin` times the box's largest
// side on every side (so no vertex sits on the lattice's boundary, where a B-spline lattice
// has fewer control points' influence), axis-aligned, with `sizes` control points per axis.
LatticeN<3> FitLattice(const SurfaceMesh& mesh, const LatticeN<3>::Sizes& sizes, BasisKind basis, double margin);

// n points on the surface, spread by area: point i takes the triangle where the cumulative
// area passes (i + ½)/n of the total, and a place in it from the R2 low-discrepancy sequence
// (Roberts 2018). So every triangle gets n·area/total points, to within one.
std::vector<Eigen::Vector3d> SampleSurface(const SurfaceMesh& mesh, int n);

// About n points filling the enclosed volume: the centres of a cubic grid of spacing
// h = (V/n)^(1/3) over the bounding box whose |winding number| is ≥ 1/2, so each point stands
// for an equal cube of the solid. Throws InputError when the mesh encloses no volume or no
// grid point falls inside (too few points for a thin part).
std::vector<Eigen::Vector3d> SampleVolume(const SurfaceMesh& mesh, int n);

}  // namespace wobble
