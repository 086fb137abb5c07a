// Target files: what a fit should match (`wobble fit pose`, `wobble fit trajectory`).
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
#pragma once

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

namespace wobble::formats {

// One correspondence: a body point (a mass point, or lattice coordinates) and where it should be.
struct PointTarget {
  int mass_point = -1;                                       // >= 0: this mass point
  Eigen::Vector2d lattice_coords = Eigen::Vector2d::Zero();  // used when mass_point < 0
  Eigen::Vector2d position = Eigen::Vector2d::Zero();        // world
  double weight = 1.0;
  int line = 0;  // source line, for errors found later (a mass point the body does not have)
};

struct TargetFrame {
  double time = 0.0;
  std::vector<PointTarget> points;
  int line = 0;
};

struct TargetCurve {
  std::vector<Eigen::Vector2d> points;
  bool closed = false;
};

struct TargetFile {
  std::string file;                    // name used in errors
  std::vector<PointTarget> points;     // correspondences (no frames)
  std::vector<TargetCurve> polylines;  // curve target
  std::vector<Eigen::Vector2d> cloud;  // curve target
  std::vector<TargetFrame> frames;     // trajectory
  bool has_correspondences() const { return !points.empty(); }
  bool has_curve() const { return !polylines.empty() || !cloud.empty(); }
  bool is_trajectory() const { return !frames.empty(); }
};

// Reads a target file; ParseError (line 0) if it cannot be opened or holds nothing.
TargetFile ReadTargetFile(const std::string& path);
TargetFile ParseTargets(std::istream& in, const std::string& name_for_errors);

// Checks that every mass point index exists in a body with `num_points` points: ParseError at
// the line of the first one that does not.
void CheckMassPointIndices(const TargetFile& targets, int num_points);

}  // namespace wobble::formats
