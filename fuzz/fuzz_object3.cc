// formats::ParseObject<3> on arbitrary bytes: a BodyDefN<3> or a ParseError, nothing else. Mesh
// lines get the stand-in reader of fuzz_common.h ("mesh box", "mesh sheet").
#include <sstream>
#include <stdexcept>

#include "fuzz_common.h"


extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const BodyDefN<3> def = formats::ParseObject<3>(in, "fuzz.obj", fuzz::StandInMesh);
    // what object_file.h promises: at least one positive mass point, each inside the lattice
    if (def.masses.empty() || def.masses.size() != def.mass_positions.size()) std::abort();
    for (double m : def.masses)
      if (!(m > 0)) std::abort();
    for (const auto& shape : def.shapes)
      if (shape.points.size() < 2) std::abort();
    if (def.lattice.size() <= 64) BodyModelN<3> body(def, {});
  });
  return 0;
}
