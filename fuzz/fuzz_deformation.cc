// formats::ParseDeformations on arbitrary bytes over the table's 4 x 4 lattice (matrix modes and
// 2D generator lines); modes that fit it are then given to BodyModel as `load_def` and
// `wobble simulate --modes` do.
#include <sstream>

#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const BodyModel& table = *fuzz::TableBody();
    std::vector<DeformationMode> modes = formats::ParseDeformations(in, "fuzz.def", table.lattice());
    if (modes.empty()) std::abort();  // the reader promises at least one mode
    for (const DeformationMode& m : modes) {
      if (m.lattice_size[0] < 2 || m.lattice_size[1] < 2) std::abort();
      if (!(m.stiffness >= 0) || !(m.damping >= 0)) std::abort();
      if (m.displacement.size() != size_t(m.lattice_size[0]) * size_t(m.lattice_size[1])) std::abort();
      for (const Eigen::Vector2d& d : m.displacement)
        if (!d.allFinite()) std::abort();
    }
    if (modes.front().lattice_size == table.lattice().sizes() &&
        modes.size() <= 8)
      BodyModel body(table.def(), std::move(modes));
  });
  return 0;
}
