// What every fuzz target shares: the one list of expected failures, the table bodies of data/,
// the stand-in mesh reader, and a reader of typed values from the fuzzer's bytes.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/core/errors.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/formats/parse_error.h"
#include "wobble/script/interpreter.h"
#include "support/source_paths.h"

namespace wobble::fuzz {

inline const std::string kDataDir = wobble::test_env::DataDir();

// Runs f; the failures hostile input is allowed to cause (a named error of core/errors.h, a
// reader's ParseError, a stopped simulation) are swallowed. Anything else escapes: an
// uncaught exception aborts, and libFuzzer (or the replay test) reports it.
template <class F> void IgnoringExpectedErrors(F&& f) {
  try {
    f();
  } catch (const formats::ParseError&) {
  } catch (const std::invalid_argument&) {  // InputError and LimitExceeded (errors.h)
  } catch (const NumericalStop&) {          // script::SimulationStopped too
  }
}

// The table of Fig. 1.2 with its four modes, read once per process.
inline std::shared_ptr<const BodyModel> TableBody() {
  static const std::shared_ptr<const BodyModel> body = std::make_shared<const BodyModel>(
      formats::ReadObjectFile(kDataDir + "/table.obj"), formats::ReadDeformationFile(kDataDir + "/table_modes.def"));
  return body;
}

// The 3D table (data/table3.obj, mass points only) with its four modes, read once per process.
inline std::shared_ptr<const BodyModelN<3>> Table3Body() {
  static const std::shared_ptr<const BodyModelN<3>> body = [] {
    BodyDefN<3> def = formats::ReadObjectFile<3>(kDataDir + "/table3.obj");
    auto modes = formats::ReadDeformationFile(kDataDir + "/table3_modes.def3", def.lattice);
    return std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes));
  }();
  return body;
}

// The mesh reader of the fuzzers (no VTK here): "box" is a closed 100 x 50 x 80 box, "sheet" a
// flat square (no volume), anything else fails as a reader would.
inline SurfaceMesh StandInMesh(const std::string& path) {
  SurfaceMesh mesh;
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

// Typed values from the front of the input, like LLVM's FuzzedDataProvider but reading plain
// bytes (its tail-first layout buys nothing here). Past the end every value is zero.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  uint8_t Byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  // A finite value in [lo, hi] from two bytes.
  double InRange(double lo, double hi) {
    const unsigned raw = (unsigned(Byte()) << 8) | Byte();
    return lo + (hi - lo) * (raw / 65535.0);
  }
  // Mostly a plausible value in [lo, hi]; sometimes one a thousand times out of it, or one of
  // the values readers and steps must refuse or survive (NaN, infinities, the extremes). Not
  // any bit pattern: huge finite values (1e300) are a known open class of their own.
  double Value(double lo, double hi) {
    const uint8_t kind = Byte();
    if (kind < 208) return InRange(lo, hi);
    if (kind < 240) return InRange(lo * 1e3, hi * 1e3);
    static const double kSpecial[] = {std::nan(""), HUGE_VAL, -HUGE_VAL, 0.0, -0.0, 1e-300, -1e-300, 5e-324};
    return kSpecial[kind % (sizeof kSpecial / sizeof kSpecial[0])];
  }
  int Int(int lo, int hi) { return lo + int(Byte() % unsigned(hi - lo + 1)); }
  bool empty() const { return pos_ >= size_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

inline std::string AsText(const uint8_t* data, size_t size) { return std::string(reinterpret_cast<const char*>(data), size); }

}  // namespace wobble::fuzz
