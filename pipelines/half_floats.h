// float -> IEEE 754 binary16 ("half", OpenEXR's HALF) for whole channels. The x86 F16C
// instruction converts 8 values per instruction where the CPU has it (checked at run time);
// elsewhere, and for the tail, Imath's conversion. Both round to nearest, ties to even, so the
// bits are the same except a NaN's payload (still a NaN). Imath's scalar conversion was a third
// of an EXR frame's writing time (2 ms a 640x480 channel).
#pragma once

#include <cstddef>
#include <cstdint>

namespace wobble::pipelines {

void FloatsToHalves(const float* in, size_t n, std::uint16_t* out);

}  // namespace wobble::pipelines
