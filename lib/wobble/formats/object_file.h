// Object files: a body's lattice, mass points and drawing geometry (§4.2, Fig. 4.3).
//
// Line based; '#' starts a comment anywhere on a line; blank lines are ignored. Statements:
//
//   name <word>                                   optional (at most once); default: the file stem
//   lattice <x0> <y0> <width> <height> [<num_s> <num_t> [bernstein|bspline]]
//                                                 exactly once. Axis-aligned: origin (x0, y0),
//                                                 axis_s = (width, 0), axis_t = (0, height),
//                                                 width, height > 0; default 4 x 4 Bernstein.
//                                                 Put (x0, y0) = (0, 0) to follow the thesis
//                                                 (body origin at the lattice's bottom-left, §4.3).
//   mass <x> <y> <m>                              a mass point in the body frame, m > 0; at
//                                                 least one; it must lie inside the lattice
//                                                 (0 <= s, t <= 1 within 1e-9).
//   polyline <x1> <y1> <x2> <y2> ... [closed]     drawing geometry (drawn, never simulated),
//                                                 at least 2 points; "closed" joins last to first.
//
// Statements may come in any order. World and body frames have y up (gravity is −y).
// Example (data/table.obj, the table of Fig. 1.2 / Fig. 4.3):
//
//   lattice 0 0 300 100
//   polyline 0 100 300 100
//   mass 0 100 50
//   ...
//
// Every problem is a ParseError naming the file and line and what was expected.
#pragma once

#include <istream>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

// Reads an object file; ParseError (line 0) if it cannot be opened.
BodyDef ReadObjectFile(const std::string& path);

// Parses an object description from `in`; `name_for_errors` is the file name used in errors
// and, through its stem, the default body name.
BodyDef ParseObject(std::istream& in, const std::string& name_for_errors);

// 3D object files: the same statements with a third coordinate, after a first line
// 'dimension 3' (a 2D file may start with 'dimension 2'):
//
//   dimension 3
//   name <word>
//   lattice <x0> <y0> <z0> <width> <height> <depth> [<num_s> <num_t> <num_u> [bernstein|bspline]]
//   mass <x> <y> <z> <m>
//   polyline <x1> <y1> <z1> <x2> <y2> <z2> ... [closed]
//
// s runs along x, t along y (up), u along z; the body origin is the lattice corner (x0, y0, z0).
BodyDef3 ReadObjectFile3(const std::string& path);
BodyDef3 ParseObject3(std::istream& in, const std::string& name_for_errors);
// 3 for a file whose first statement is 'dimension 3', else 2 (the readers report the rest).
int ObjectFileDimension(const std::string& path);

}  // namespace wobble::formats
