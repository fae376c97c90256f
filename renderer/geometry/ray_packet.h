#pragma once
// Up to eight rays axis by axis, a lane per ray: what the packet walk (bvh_packet_body.h) and the
// packet leaf test (triangle4_packet.h) read. A Ray is eight floats (origin, direction, t_min,
// t_max), so a full packet is an 8x8 transpose of its rays: 16 loads and 24 shuffles, where a lane
// at a time took 7 scalar copies a ray and loads that could not be forwarded from them.
#include <cstddef>
#include <immintrin.h>

#include "renderer/geometry/ray.h"

namespace farm {

static_assert(sizeof(Ray) == 8 * sizeof(float) && offsetof(Ray, direction) == 3 * sizeof(float) &&
              offsetof(Ray, t_min) == 6 * sizeof(float) && offsetof(Ray, t_max) == 7 * sizeof(float));

// The rows of a packet: origin x, y, z, direction x, y, z, t_min, t_max.
enum RayPacketRow { kOriginX, kOriginY, kOriginZ, kDirectionX, kDirectionY, kDirectionZ, kTMin, kTMax };

// The lanes of an 8-lane mask, without the library call std::popcount is on a CPU without
// POPCNT (the build's baseline x86-64).
constexpr int lane_count(unsigned lanes) {
  lanes &= 0xFFu;
  lanes = (lanes & 0x55u) + (lanes >> 1 & 0x55u);
  lanes = (lanes & 0x33u) + (lanes >> 2 & 0x33u);
  return static_cast<int>((lanes & 0x0Fu) + (lanes >> 4));
}
static_assert(lane_count(0xFFu) == 8 && lane_count(0xA5u) == 4 && lane_count(0u) == 0);

// All bits set in the lanes of `lanes`, clear in the others.
__attribute__((target("avx2"))) inline __m256 lane_mask(unsigned lanes) {
  const __m256i bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  return _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(static_cast<int>(lanes)), bit), bit));
}

// Half `half` (floats 0-3 or 4-7) of rays[ray] and of rays[ray + 4], side by side.
__attribute__((target("avx2"))) inline __m256 load_ray_halves(const Ray* rays, int ray, int half) {
  const float* first = &rays[ray].origin.x + 4 * half;
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(first)), _mm_loadu_ps(first + 32), 1);
}

// rows[r][i] is row r of rays[i] for each bit i of `lanes`, and `absent` (every row) in the other
// lanes. Reads rays[i] only for the lanes asked.
__attribute__((target("avx2"))) inline void load_ray_packet(const Ray* rays, unsigned lanes, const float* absent,
                                                            __m256 (&rows)[8]) {
  if (lanes == 0xFFu) {
    // Each half of a ray (floats 0-3, 4-7) beside the same half of the ray four on, then a 4x4
    // transpose within each 128-bit lane. Loads of 16 bytes straight into registers: no array of
    // whole rays for the compiler to spill in halves and reload whole, which stalls.
    for (int half = 0; half < 2; ++half) {
      const __m256 r0 = load_ray_halves(rays, 0, half), r1 = load_ray_halves(rays, 1, half);
      const __m256 r2 = load_ray_halves(rays, 2, half), r3 = load_ray_halves(rays, 3, half);
      const __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
      const __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
      rows[4 * half + 0] = _mm256_shuffle_ps(t0, t2, 0x44);
      rows[4 * half + 1] = _mm256_shuffle_ps(t0, t2, 0xEE);
      rows[4 * half + 2] = _mm256_shuffle_ps(t1, t3, 0x44);
      rows[4 * half + 3] = _mm256_shuffle_ps(t1, t3, 0xEE);
    }
    return;
  }
  alignas(32) float values[8][8];
  for (int i = 0; i < 8; ++i) {
    const float* from = (lanes >> i & 1u) ? &rays[i].origin.x : absent;
    for (int r = 0; r < 8; ++r) values[r][i] = from[r];
  }
  for (int r = 0; r < 8; ++r) rows[r] = _mm256_load_ps(values[r]);
}

}  // namespace farm
