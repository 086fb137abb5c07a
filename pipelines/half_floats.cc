#include "pipelines/half_floats.h"

#include <Imath/half.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define WOBBLE_HAVE_F16C_PATH 1
#endif

namespace wobble::pipelines {
namespace {

void ScalarFloatsToHalves(const float* in, size_t n, std::uint16_t* out) {
  for (size_t i = 0; i < n; ++i) out[i] = Imath::half(in[i]).bits();
}

#ifdef WOBBLE_HAVE_F16C_PATH
__attribute__((target("avx,f16c"))) void F16cFloatsToHalves(const float* in, size_t n, std::uint16_t* out) {
  size_t i = 0;
  for (; i + 8 <= n; i += 8)
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i),
                     _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT));
  ScalarFloatsToHalves(in + i, n - i, out + i);
}
#endif

}  // namespace

void FloatsToHalves(const float* in, size_t n, std::uint16_t* out) {
#ifdef WOBBLE_HAVE_F16C_PATH
  static const bool f16c = __builtin_cpu_supports("avx") && __builtin_cpu_supports("f16c");
  if (f16c) return F16cFloatsToHalves(in, n, out);
#endif
  ScalarFloatsToHalves(in, n, out);
}

}  // namespace wobble::pipelines
