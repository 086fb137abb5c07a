// Deformation files: the matrices d of a body's deformation modes (§4.3, Eq. 4.2), 2D and 3D,
// in one grammar read by one parser: the format of the thesis' §4.10.1 (x: and y: matrices),
// an optional header line per mode, and named generators that compute a mode over the body's
// lattice (docs/deformation_files.md has the grammar with examples).
//
// Line based; '#' starts a comment anywhere on a line; blank lines are ignored.
//
//   file      = [ "dimension" ("2" | "3") ] mode { mode }
//   mode      = [ header ] matrix             matrix modes: 2D only; a header is optional
//             | header generator { generator } generator modes: 2D and 3D; displacements add
//   header    = "mode" <name> [stiffness <K>] [damping <c>] [active|passive]
//   matrix    = "x:" row { row } "y:" row { row }      (a row may start on the keyword's line)
//   generator = bend | twist | squash | shear | taper | point   (one line each, below)
//
// Dimension. The 'dimension' line, when present, must be the first line. Without it a file is
// 2D: every file of the thesis' format, and every 2D file wobble wrote before the line
// existed, has none. So a 3D file must start with 'dimension 3'; reading a file of one
// dimension for a body of the other is a ParseError on line 1.
//
// Matrices (2D). x: and y: are matrices with one row per lattice row and one number per
// lattice column:
//   * rows run from the BOTTOM lattice row (t = 0) upward to the top (t = 1);
//   * columns run from s = 0 (left) to s = 1 (right).
// So a file for a num_s x num_t lattice has num_t rows of num_s numbers in each section, and the
// number in row j, column i is d_ij, stored in DeformationMode::displacement at flat index
// i*num_t + j (i along s, j along t, as everywhere in wobble). Every x: row has the same count
// and y: has the same shape as x:. The first matrix mode fixes the lattice size of the file;
// every later one must match it. Sizes of at least 2 x 2 (the lattice the body's object file
// sets must match; BodyModel checks that). Matrix modes need no lattice to be read.
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
// A mode without a header (matrix modes only) is named after the file stem: "<stem>" when the
// file holds a single mode, "<stem>_<k>" for the k-th mode (k = 1, 2, ...) when it holds several.
//
// Generators: modes computed over the body's lattice, so that the common shapes need no typing
// of every control point. Axes x, y[, z] are the lattice's s, t[, u] axes and ê_a the unit
// vector along axis a; u_a ∈ [0, 1] is a control point's lattice coordinate along axis a, r its
// offset from the lattice centre (origin + ½ Σ axes) and r⊥ = r − (ê·r)ê the part of r across
// the named axis. Displacement d of each control point at γ = 1:
//   bend <along> <toward> <amount>     d = amount (1 − (2u_along − 1)²) ê_toward: an arch whose
//                                      middle moves by <amount> (length), ends fixed
//   twist <axis> <degrees>             3D only: d = θ (u − ½) ê × r⊥, the ends turn by
//                                      ±degrees/2 about the centre line (linearized, as every
//                                      mode is linear in γ)
//   squash <axis> <fraction>           d = f ((ê·r) ê − ½ r⊥): longer by f along the axis,
//                                      thinner by f/2 across (γ < 0 squashes)
//   shear <axis> <toward> <amount>     d = amount (u − ½) ê_toward (the ends part by <amount>)
//   taper <axis> <fraction>            d = f (u − ½) r⊥: cross-sections scale by 1 ± f/2 at the ends
//   point <i> <j> [<k>] <dx> <dy> [<dz>]  adds (dx, dy[, dz]) to control point (i, j[, k])
// In 2D the axes are x and y, and each generator is its 3D field restricted to the lattice's
// plane (the plane through the centre, where r has no z part): the same formulas in two
// components. So the 2D squash keeps the area only to within f/2 (its 3D form keeps the volume
// to first order, thinning two cross axes). twist has no 2D form and is refused ("twist needs
// dimension 3"): about an axis in the plane, ê × r⊥ points out of the plane, and about the
// normal z its angle varies along z, across which a 2D lattice has no extent; either way the
// restriction to the plane is zero. Generator modes fit any lattice size; 'point' lines name
// indices within it.
//
// Every problem (empty file, wrong row or column count, a non-number, a missing y: section,
// a lattice size that differs from the first mode's, an unknown keyword, header option, axis or
// generator, a generator of the wrong dimension) is a ParseError naming the file and line and
// what was expected there.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "wobble/body/lattice.h"
#include "wobble/body/mode.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

// Reads every mode of a deformation file over the lattice of the body the modes are for (its
// dimension is the file's); ParseError (line 0) if it cannot be opened. Generator lines are
// computed over the lattice: pass it whenever it is known.
template <int Dim>
std::vector<DeformationModeN<Dim>> ReadDeformationFile(const std::string& path, const LatticeN<Dim>& lattice);
// A 2D file without the body's lattice: its generator lines are a ParseError.
std::vector<DeformationMode> ReadDeformationFile(const std::string& path);

// Parses deformation modes from `in`; `name_for_errors` is the file name used in errors and,
// through its stem, the default mode names.
template <int Dim>
std::vector<DeformationModeN<Dim>> ParseDeformations(std::istream& in, const std::string& name_for_errors,
                                                     const LatticeN<Dim>& lattice);
std::vector<DeformationMode> ParseDeformations(std::istream& in, const std::string& name_for_errors);

}  // namespace wobble::formats
