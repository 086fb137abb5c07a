// The plain (double) steps of the 2D and 3D bodies, instantiated once for every unit that
// steps a body (step.h declares them extern).
#include "wobble/dynamics/step.h"

namespace wobble {

WOBBLE_DOUBLE_STEP(, 2);
WOBBLE_DOUBLE_STEP(, 3);

}  // namespace wobble
