#pragma once
// Branch-free float versions of the few transcendental functions FLIP evaluates per pixel (cube
// roots for CIELAB, powers for the error remapping). glibc's cbrtf and powf are scalar calls
// that keep the per-pixel loops from vectorising and would cost more than all the filtering;
// these are plain arithmetic and bit operations the compiler turns into SIMD code. Relative
// error is a few 1e-7, far below anything the metric resolves.
#include <algorithm>
#include <bit>
#include <cstdint>

namespace farm::flip_detail {

// log2(x) for x >= 1e-30 (no zero, infinity or NaN).
inline float fast_log2(float x) {
  const auto bits = std::bit_cast<std::int32_t>(x);
  auto exponent = static_cast<float>(((bits >> 23) & 0xff) - 127);
  float m = std::bit_cast<float>((bits & 0x007fffff) | 0x3f800000);  // mantissa in [1, 2)
  // Centre the mantissa on 1, in [sqrt(1/2), sqrt(2)), so that the series below converges fast.
  const bool high = m > 1.41421356f;
  m = high ? 0.5f * m : m;
  exponent = high ? exponent + 1.0f : exponent;
  // ln(m) = 2 atanh(s) with s = (m - 1) / (m + 1), |s| < 0.172: five odd terms reach 1e-9.
  const float s = (m - 1.0f) / (m + 1.0f);
  const float s2 = s * s;
  const float ln_m =
      s * (2.0f + s2 * (2.0f / 3.0f + s2 * (2.0f / 5.0f + s2 * (2.0f / 7.0f + s2 * (2.0f / 9.0f)))));
  return exponent + ln_m * 1.44269504f;  // 1 / ln 2
}

// 2^x; x below -126 gives 2^-126 (callers treat that as zero), above 126 gives 2^126.
inline float fast_exp2(float x) {
  x = std::min(std::max(x, -126.0f), 126.0f);
  // Nearest integer n (truncating a positive number is flooring it) and the rest f in [-0.5, 0.5].
  const std::int32_t n = static_cast<std::int32_t>(x + 128.5f) - 128;
  const float f = x - static_cast<float>(n);
  // 2^f = e^(f ln 2) by Taylor series; |f ln 2| <= 0.347 leaves the 8th term below 1e-8.
  const float t = f * 0.693147181f;
  const float e =
      1.0f +
      t * (1.0f + t * (1.0f / 2.0f +
                       t * (1.0f / 6.0f +
                            t * (1.0f / 24.0f + t * (1.0f / 120.0f + t * (1.0f / 720.0f + t * (1.0f / 5040.0f)))))));
  return e * std::bit_cast<float>((n + 127) << 23);
}

// x^e for x >= 0 and e >= 0, with 0^0 = 1 as std::pow has it.
inline float fast_pow(float x, float e) {
  const float r = fast_exp2(e * fast_log2(std::max(x, 1e-30f)));
  return x > 0.0f ? r : (e == 0.0f ? 1.0f : 0.0f);
}

// The cube root of t in [1e-4, 2].
inline float fast_cbrt(float t) {
  // A guess within a few per cent from the bit pattern (dividing the exponent by three), then
  // two Halley steps, each of which triples the number of correct digits.
  const auto bits = static_cast<float>(std::bit_cast<std::int32_t>(t));
  float y = std::bit_cast<float>(static_cast<std::int32_t>(bits * (1.0f / 3.0f)) + 709921077);
  for (int i = 0; i < 2; ++i) {
    const float y3 = y * y * y;
    y *= (y3 + 2.0f * t) / (2.0f * y3 + t);
  }
  return y;
}

}  // namespace farm::flip_detail
