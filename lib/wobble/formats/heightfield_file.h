// A heightfield file: the 3D ground y = h(x, z) on a regular grid (dynamics/heightfield.h).
//     # comments and blank lines anywhere
//     origin X0 Z0
//     spacing DX DZ
//     h(0,0) h(1,0) ... h(nx-1,0)        <- the row at z0
//     h(0,1) ...                         <- the row at z0 + dz, and so on
//     region X0 Z0 X1 Z1 NAME VALUE [NAME VALUE ...]   <- optional, anywhere after spacing
// Heights are separated by commas or blanks (numpy.savetxt writes either); every row has the
// same count, at least two, and there are at least two rows. A `region` gives the cells whose
// centres lie in [X0, X1] x [Z0, Z1] their own penalty constants (grconst, grdam, frconst,
// frsin: the names `set` gives the ground's), later regions over earlier ones.
#pragma once

#include <memory>
#include <string>

#include "wobble/dynamics/heightfield.h"

namespace wobble::formats {

// Throws ParseError "FILE:LINE: ..." on a missing origin or spacing, a bad number, rows of
// unequal length, a grid Heightfield::Make refuses, or a region with a bad name or value or
// no cell in it.
std::shared_ptr<const Heightfield> ReadHeightfieldFile(const std::string& path);

// Written atomically (a region per cell with constants of its own); ReadHeightfieldFile reads
// back the same heights and constants bit for bit.
void WriteHeightfieldFile(const std::string& path, const Heightfield& field);

}  // namespace wobble::formats
