// formats::ParseDeformations on arbitrary bytes over the 3D table's 4 x 4 x 4 lattice: modes or
// a ParseError; the modes are then given to BodyModelN<3> and checked as `wobble condition check`
// does.
#include <sstream>

#include "fuzz_common.h"
#include "wobble/analysis/conditioning.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  static const BodyDefN<3> table = formats::ReadObjectFile<3>(fuzz::kDataDir + "/table3.obj");
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    std::vector<DeformationModeN<3>> modes = formats::ParseDeformations(in, "fuzz.def3", table.lattice);
    if (modes.empty()) std::abort();  // the reader promises at least one mode
    for (const DeformationModeN<3>& m : modes) {
      if (m.lattice_size != table.lattice.sizes() || int(m.displacement.size()) != table.lattice.size()) std::abort();
      if (!(m.stiffness >= 0) || !(m.damping >= 0)) std::abort();
      // finite inputs may still add up to inf (1e308 twice): the body model must refuse that
    }
    if (modes.size() <= 8) {
      const BodyModelN<3> body(table, std::move(modes));
      analysis::CheckModeSet(body);
    }
  });
  return 0;
}
