// Deformation files: the matrices d of a body's deformation modes (§4.3, Eq. 4.2), in the
// format of the thesis' §4.10.1, extended with an optional header line per mode.
//
// Format. Line based; '#' starts a comment anywhere on a line; blank lines are ignored.
// A file holds one or more modes; each mode is
//
//   mode <name> [stiffness <K>] [damping <c>] [active|passive]     optional header
//   x: <d_x of row 0>                                              the row may also start on the next line
//      <d_x of row 1>
//      ...
//   y: <d_y of row 0>
//      ...
//
// x: and y: are matrices with one row per lattice row and one number per lattice column:
//   * rows run from the BOTTOM lattice row (t = 0) upward to the top (t = 1);
//   * columns run from s = 0 (left) to s = 1 (right).
// So a file for a num_s x num_t lattice has num_t rows of num_s numbers in each section, and the
// number in row j, column i is d_ij, stored in DeformationMode::displacement at flat index
// i*num_t + j (i along s, j along t, as everywhere in wobble). Every x: row has the same count
// and y: has the same shape as x:. The first mode fixes the lattice size of the file; every
// later mode must match it. Sizes of at least 2 x 2 (the lattice the body's object file sets
// must match; BodyModel checks that).
//
// Values are displacements in body-frame units added to the lattice points at amplitude γ = 1
// (Eq. 4.2): lattice point (i, j) moves to L_ij + Σ_k γ_k d^k_ij. World and body frames have
// y up and gravity along −y. With rows read bottom to top, the §4.10.1 matrix
//
//   x: 150 150 -150 -150        (row 0, t = 0: the feet move inward)
//       50  50  -50  -50
//      -50 -50   50   50
//     -150 -150 150  150        (row 3, t = 1: the top spreads)
//   y: 0 100 100 0              (four such rows: the middle columns rise)
//
// at γ = +0.2 arches the table of Fig. 1.2 (the middle of its top rises by 15), as in Fig. 4.6.
//
// Header options: stiffness K of the mode's potential V = K γ² (§4.7; default 0), damping c of
// the generalized force −c γ̇ (default 0), active (driven by a controller, chapter 5) or
// passive (default). Both K and c must be >= 0. Mode names must be unique within a file.
// A mode without a header is named after the file stem: "<stem>" when the file holds a single
// mode, "<stem>_<k>" for the k-th mode (k = 1, 2, ...) when it holds several.
//
// Every problem (empty file, wrong row or column count, a non-number, a missing y: section,
// a lattice size that differs from the first mode's, an unknown keyword or header option) is a
// ParseError naming the file and line.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "wobble/body/lattice.h"
#include "wobble/body/mode.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

// Reads every mode of a deformation file; ParseError (line 0) if it cannot be opened.
std::vector<DeformationMode> ReadDeformationFile(const std::string& path);

// Parses deformation modes from `in`; `name_for_errors` is the file name used in errors and,
// through its stem, the default mode names.
std::vector<DeformationMode> ParseDeformations(std::istream& in, const std::string& name_for_errors);

// 3D deformation files: modes made by named generators over the body's lattice, so that the
// common shapes need no typing of every control point (a 4x4x4 lattice has 64). Format:
//
//   dimension 3                                        first line
//   mode <name> [stiffness <K>] [damping <c>] [active|passive]
//     <generator>                                      one or more; their displacements add
//
// Axes x, y, z are the lattice's s, t, u axes; u_a ∈ [0, 1] is a control point's lattice
// coordinate along axis a, r its offset from the lattice centre and r⊥ the part of r across
// the named axis. Generators (displacement d of each control point at γ = 1):
//   bend <along> <toward> <amount>     d = amount (1 − (2u_along − 1)²) ê_toward: an arch whose
//                                      middle moves by <amount> (length), ends fixed
//   twist <axis> <degrees>             d = θ (u − ½) ê × r⊥: the ends turn by ±degrees/2 about
//                                      the centre line (linearized, as every mode is linear in γ)
//   squash <axis> <fraction>           d = f ((ê·r) ê − ½ r⊥): longer by f along the axis,
//                                      thinner by f/2 across (γ < 0 squashes)
//   shear <axis> <toward> <amount>     d = amount (u − ½) ê_toward (the ends part by <amount>)
//   taper <axis> <fraction>            d = f (u − ½) r⊥: cross-sections scale by 1 ± f/2 at the ends
//   point <i> <j> <k> <dx> <dy> <dz>   adds (dx, dy, dz) to control point (i, j, k)
// Modes from generators fit any lattice size; 'point' lines name indices within it. Every
// problem is a ParseError naming the file and line (data/table3_modes.def3 is an example).
std::vector<DeformationMode3> ReadDeformationFile3(const std::string& path, const Lattice3& lattice);
std::vector<DeformationMode3> ParseDeformations3(std::istream& in, const std::string& name_for_errors,
                                                 const Lattice3& lattice);

}  // namespace wobble::formats
