#pragma once
// The point at a fraction of a turn round the unit circle, (cos 2 pi u, sin 2 pi u), for the
// samplers that pick an angle from a uniform number (cosine-weighted and visible-normal
// directions, points on lights). Inline float arithmetic of our own instead of libm's sincosf:
// on the path tracer's critical path (the angle decides the next ray) the call cost 4.7% of a
// Cornell box render's time for 1.4% of its instructions (docs/architecture.md, 8.1), and a
// polynomial written out is the same bits on every machine and in every SIMD lane.
#include <bit>
#include <cstdint>

namespace farm {

struct CosSin {
  float cos = 1.0f, sin = 0.0f;
};

// Within 1.7 ulp of the true values (9e-8 absolute) for u in [0, 1); exact at the quarter turns.
// Any finite u works, but the reduction loses precision as |u| grows past a few turns.
inline CosSin unit_circle_point(float u) {
  // The nearest quarter turn q and what is left, f in [-1/2, 1/2] quarter turns: 4u is exact, the
  // 1.5 * 2^23 trick rounds it to an integer (to even, in float alone) and leaves q's low bits
  // in the sum's mantissa, and x - q is exact (Sterbenz).
  const float x = 4.0f * u;
  constexpr float kRound = 12582912.0f;
  const float rounded = x + kRound;
  const std::uint32_t quarter = std::bit_cast<std::uint32_t>(rounded) & 3u;
  const float f = x - (rounded - kRound);
  // sin(pi f / 2) and cos(pi f / 2) on [-1/2, 1/2]: minimax polynomials fitted for this use
  // (odd degree 7, even degree 8; Horner in float, no fused multiply-add).
  const float f2 = f * f;
  const float s = f * (1.5707963705062866f +
                       f2 * (-0.6459634900093079f + f2 * (0.07968003302812576f + f2 * -0.004601657390594482f)));
  const float c =
      1.0f + f2 * (-1.2337005138397217f +
                   f2 * (0.25366920232772827f + f2 * (-0.02086007222533226f + f2 * 0.0009036316769197583f)));
  // Turned by q quarters: (c, s), (-s, c), (-c, -s), (s, -c).
  const bool odd = (quarter & 1u) != 0;
  const float cos_part = odd ? s : c, sin_part = odd ? c : s;
  const std::uint32_t cos_sign = ((quarter + 1u) & 2u) << 30, sin_sign = (quarter & 2u) << 30;
  return {std::bit_cast<float>(std::bit_cast<std::uint32_t>(cos_part) ^ cos_sign),
          std::bit_cast<float>(std::bit_cast<std::uint32_t>(sin_part) ^ sin_sign)};
}

}  // namespace farm
