// Target files: what a fit should match (`wobble fit pose`, `wobble fit trajectory`).
// A 2D file (below) fits a 2D object; a 3D object's file starts with 'dimension 3' (further
// below).
//
// Line based like the object file: '#' starts a comment anywhere on a line; blank lines are
// ignored; every problem is a ParseError "FILE:LINE: what was expected". Statements:
//
//   point <k> <x> <y> [weight <w>]       mass point k (0-based, in the order of the object
//                                        file's 'mass' lines) should be at world (x, y)
//   sample <s> <t> <x> <y> [weight <w>]  the body point at lattice coordinates (s, t), e.g. a
//                                        point of the drawing, should be at (x, y); 0 <= s,t <= 1
//   polyline <x1> <y1> <x2> <y2> ... [closed]
//                                        a target curve without correspondences (at least 2
//                                        points; "closed" joins the last point to the first)
//   cloud <x> <y>                        one unordered target point without correspondence
//   frame <time>                         starts a frame of a trajectory: the point/sample lines
//                                        that follow belong to it; times strictly increase
//
// A file holds correspondences (point/sample), or a curve target (polyline/cloud), not both.
// A file with 'frame' lines is a trajectory: every point/sample line is inside a frame, and
// polyline/cloud are not allowed. Weights are > 0 (default 1). World frame, y up.
// Examples: data/table_pose.tgt, data/table_curve.tgt, data/table_keys.tgt.
//
// 3D (a 3D object's targets): the first statement is 'dimension 3', then
//
//   point <k> <x> <y> <z> [weight <w>]         mass point k should be at (x, y, z)
//   sample <s> <t> <u> <x> <y> <z> [weight <w>] the body point at lattice coordinates (s, t, u)
//   cloud <x> <y> <z>                          an unordered target point (e.g. of a scan)
//   mesh <FILE>                                a target surface (.obj .stl .ply .vtp, read by
//                                              VTK; relative to the target file's folder)
//   frame <time>                               as in 2D
//
// with the same rules (cloud and mesh form the target without correspondences; there are no
// polylines). Examples: data/pot3_pose.tgt, data/pot3_squashed.tgt.
#pragma once

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

#include "wobble/body/surface_mesh.h"
#include "wobble/formats/object_file.h"

namespace wobble::formats {

// One correspondence: a body point (a mass point, or lattice coordinates) and where it should be.
template <int Dim> struct PointTargetN {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  int mass_point = -1;              // >= 0: this mass point
  Vec lattice_coords = Vec::Zero();  // used when mass_point < 0
  Vec position = Vec::Zero();        // world
  double weight = 1.0;
  int line = 0;  // source line, for errors found later (a mass point the body does not have)
};

template <int Dim> struct TargetFrameN {
  double time = 0.0;
  std::vector<PointTargetN<Dim>> points;
  int line = 0;
};

struct TargetCurve {
  std::vector<Eigen::Vector2d> points;
  bool closed = false;
};

template <int Dim> struct TargetFileN {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  std::string file;                           // name used in errors
  std::vector<PointTargetN<Dim>> points;      // correspondences (no frames)
  std::vector<TargetCurve> polylines;         // curve target (2D)
  SurfaceMesh mesh;                           // target surface (3D)
  std::vector<Vec> cloud;                     // curve / surface target
  std::vector<TargetFrameN<Dim>> frames;      // trajectory
  bool has_correspondences() const { return !points.empty(); }
  bool has_curve() const { return !polylines.empty() || !cloud.empty() || !mesh.empty(); }
  bool is_trajectory() const { return !frames.empty(); }
};

using PointTarget = PointTargetN<2>;
using TargetFrame = TargetFrameN<2>;
using TargetFile = TargetFileN<2>;

// Reads a target file of dimension Dim (2, as TargetFile, unless told); ParseError (line 0) if
// it cannot be opened or holds nothing. `read_mesh` reads a 3D file's 'mesh' statements (none:
// they are refused).
template <int Dim = 2>
TargetFileN<Dim> ReadTargetFile(const std::string& path, const MeshReader& read_mesh = nullptr);
template <int Dim = 2>
TargetFileN<Dim> ParseTargets(std::istream& in, const std::string& name_for_errors, const MeshReader& read_mesh = nullptr);

// Checks that every mass point index exists in a body with `num_points` points: ParseError at
// the line of the first one that does not.
template <int Dim> void CheckMassPointIndices(const TargetFileN<Dim>& targets, int num_points);

}  // namespace wobble::formats
