// formats::ParseObject on arbitrary bytes: a BodyDef or a ParseError, nothing else.
#include <sstream>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const BodyDef def = formats::ParseObject(in, "fuzz.obj");
    // What the readers promise the body model (object_file.h): at least one mass point, each
    // positive; a body with no modes is then buildable (small lattices only: the basis work
    // grows with the lattice and is not the reader's).
    if (def.masses.empty() || def.masses.size() != def.mass_positions.size()) std::abort();
    for (double m : def.masses)
      if (!(m > 0)) std::abort();
    if (def.lattice.size() <= 64) BodyModel body(def, {});
  });
  return 0;
}
