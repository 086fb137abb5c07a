// formats::ParseObject3 on arbitrary bytes: a BodyDef3 or a ParseError, nothing else. Mesh
// lines get a stand-in reader (no VTK here): "mesh box" is a closed 100 x 50 x 80 box, "mesh
// sheet" a flat square (no volume), anything else fails as a reader would.
#include <sstream>
#include <stdexcept>

#include "fuzz_common.h"

namespace {
wobble::SurfaceMesh StandInMesh(const std::string& path) {
  wobble::SurfaceMesh mesh;
  const std::string name = path.substr(path.find_last_of('/') + 1);
  if (name == "box") {
    for (int i = 0; i < 8; ++i) mesh.points.emplace_back(i & 1 ? 100 : 0, i & 2 ? 50 : 0, i & 4 ? 80 : 0);
    mesh.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                      {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  } else if (name == "sheet") {
    mesh.points = {{0, 0, 0}, {10, 0, 0}, {0, 0, 10}, {10, 0, 10}};
    mesh.triangles = {{0, 1, 2}, {1, 3, 2}};
  } else {
    throw std::runtime_error("no such mesh");
  }
  return mesh;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace wobble;
  fuzz::IgnoringExpectedErrors([&] {
    std::istringstream in(fuzz::AsText(data, size));
    const BodyDef3 def = formats::ParseObject3(in, "fuzz.obj", StandInMesh);
    // what object_file.h promises: at least one positive mass point, each inside the lattice
    if (def.masses.empty() || def.masses.size() != def.mass_positions.size()) std::abort();
    for (double m : def.masses)
      if (!(m > 0)) std::abort();
    for (const auto& shape : def.shapes)
      if (shape.points.size() < 2) std::abort();
    if (def.lattice.size() <= 64) BodyModel3 body(def, {});
  });
  return 0;
}
