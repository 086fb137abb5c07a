// A heightfield file: the 3D ground y = h(x, z) on a regular grid (dynamics/heightfield.h).
//     # comments and blank lines anywhere
//     origin X0 Z0
//     spacing DX DZ
//     h(0,0) h(1,0) ... h(nx-1,0)        <- the row at z0
//     h(0,1) ...                         <- the row at z0 + dz, and so on
// Heights are separated by commas or blanks (numpy.savetxt writes either); every row has the
// same count, at least two, and there are at least two rows.
#pragma once

#include <memory>
#include <string>

#include "wobble/dynamics/heightfield.h"

namespace wobble::formats {

// Throws ParseError "FILE:LINE: ..." on a missing origin or spacing, a bad number, rows of
// unequal length, or a grid Heightfield::Make refuses.
std::shared_ptr<const Heightfield> ReadHeightfieldFile(const std::string& path);

// Written atomically; ReadHeightfieldFile reads back the same heights bit for bit.
void WriteHeightfieldFile(const std::string& path, const Heightfield& field);

}  // namespace wobble::formats
