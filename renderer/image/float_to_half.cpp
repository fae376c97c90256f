#include "renderer/image/float_to_half.h"

#include <Imath/half.h>

#include <cstring>

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#include <immintrin.h>
#define FARM_HAVE_F16C_PATH 1
#endif

namespace farm {

namespace {

float float_at(const char* p) {
  float f;
  std::memcpy(&f, p, sizeof f);  // the channel's stride need not keep floats aligned
  return f;
}

void convert_in_software(const char* first, std::size_t stride, std::size_t count, std::uint16_t* out) {
  for (std::size_t i = 0; i < count; ++i, first += stride) out[i] = Imath::half(float_at(first)).bits();
}

#ifdef FARM_HAVE_F16C_PATH
__attribute__((target("avx,f16c"))) void convert_with_f16c(const char* first, std::size_t stride, std::size_t count,
                                                              std::uint16_t* out) {
  std::size_t i = 0;
  for (; i + 8 <= count; i += 8, first += 8 * stride) {
    // Built in registers: eight scalar stores read back as one vector stalled on store forwarding.
    const __m256 eight = _mm256_set_ps(float_at(first + 7 * stride), float_at(first + 6 * stride),
                                       float_at(first + 5 * stride), float_at(first + 4 * stride),
                                       float_at(first + 3 * stride), float_at(first + 2 * stride),
                                       float_at(first + stride), float_at(first));
    const __m128i halves = _mm256_cvtps_ph(eight, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), halves);
  }
  convert_in_software(first, stride, count - i, out + i);
}

// CPUID leaf 1 says AVX and F16C are there and the OS saves the AVX registers (OSXSAVE, then
// XCR0's SSE and AVX state bits). Asked directly: clang 14's __builtin_cpu_supports has no "f16c".
bool cpu_has_f16c() {
  static const bool has = [] {
    unsigned a = 0, b = 0, c = 0, d = 0;
    if (!__get_cpuid(1, &a, &b, &c, &d)) return false;
    constexpr unsigned kOsxsave = 1u << 27, kAvx = 1u << 28, kF16c = 1u << 29;
    if ((c & (kOsxsave | kAvx | kF16c)) != (kOsxsave | kAvx | kF16c)) return false;
    unsigned xcr0_low = 0, xcr0_high = 0;
    __asm__ volatile("xgetbv" : "=a"(xcr0_low), "=d"(xcr0_high) : "c"(0));
    return (xcr0_low & 0x6u) == 0x6u;
  }();
  return has;
}
#endif

}  // namespace

void floats_to_halves(const char* first, std::size_t stride, std::size_t count, std::uint16_t* out) {
#ifdef FARM_HAVE_F16C_PATH
  if (cpu_has_f16c()) {
    convert_with_f16c(first, stride, count, out);
    return;
  }
#endif
  convert_in_software(first, stride, count, out);
}

}  // namespace farm
