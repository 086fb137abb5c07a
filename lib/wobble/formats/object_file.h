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

#include <functional>
#include <istream>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

// 3D object files: the same statements with a third coordinate, after a first line
// 'dimension 3' (a 2D file may start with 'dimension 2'):
//
//   dimension 3
//   name <word>
//   lattice <x0> <y0> <z0> <width> <height> <depth> [<num_s> <num_t> <num_u> [bernstein|bspline]]
//   mass <x> <y> <z> <m>
//   polyline <x1> <y1> <z1> <x2> <y2> <z2> ... [closed]
//
// s runs along x, t along y (up), u along z. Every coordinate of the file (mass points,
// polylines, the mesh) is in the body frame, whose origin is the file's (0, 0, 0): q's
// translation puts it at t and the body turns about it (a point p at rest is at t + R p). It
// is the lattice corner only when the lattice line starts with 0 0 0 (data/table3.obj); a
// fitted lattice's corner lies wherever the mesh's box does.
//
// A 3D character may be a user's triangle mesh (issue 15), in the body frame:
//
//   mesh <file>                                   at most once; .obj .stl .ply or .vtp, read by
//                                                 VTK (a path relative to the object file's
//                                                 folder). Drawn and exported with every vertex
//                                                 moved by the FFD; never simulated.
//   lattice fit [<num_s> <num_t> <num_u> [bernstein|bspline]] [margin <f>]
//                                                 instead of 'lattice': the mesh's bounding box
//                                                 grown by f (default 0.05) of its largest side
//                                                 on every side; 4 x 4 x 4 Bernstein by default.
//                                                 With a mesh and no lattice line at all, this
//                                                 default. A lattice given by numbers must hold
//                                                 every mesh vertex.
//   sample surface|volume <points> <total mass>   mass points from the mesh, each of mass
//                                                 total / count: 'surface' spreads exactly
//                                                 <points> by area; 'volume' fills the enclosed
//                                                 solid with a cubic grid of about <points>
//                                                 (generalized winding number ≥ ½: a closed
//                                                 mesh, overlapping parts allowed). May repeat,
//                                                 and mix with 'mass' lines.
//
// Example (data/pot3.obj):
//   dimension 3
//   mesh pot3.vtp
//   lattice fit 4 4 4
//   sample volume 400 1000
//
// Mesh files are read through `read_mesh` (the app passes VTK's readers,
// pipelines/mesh_io.h); without one, a 'mesh' line is a ParseError saying so.
using MeshReader = std::function<SurfaceMesh(const std::string& path)>;

// Reads an object file of dimension Dim (2, as BodyDef, unless told); ParseError (line 0) if it
// cannot be opened, at its first statement if the file is of the other dimension.
template <int Dim = 2>
BodyDefN<Dim> ReadObjectFile(const std::string& path, const MeshReader& read_mesh = nullptr);

// Parses an object description from `in`; `name_for_errors` is the file name used in errors
// and, through its stem, the default body name.
template <int Dim = 2>
BodyDefN<Dim> ParseObject(std::istream& in, const std::string& name_for_errors, const MeshReader& read_mesh = nullptr);

// 3 for a file whose first statement is 'dimension 3', else 2 (the readers report the rest).
int ObjectFileDimension(const std::string& path);

}  // namespace wobble::formats
