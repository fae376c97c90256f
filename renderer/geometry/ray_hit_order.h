#pragma once
// Which of two hits is the closest, by one rule whatever order a structure meets them in: the
// least t, then the least object index, then the least triangle index. A ray that grazes the
// edge two triangles share, or the corner where walls meet, hits both at the same t; with this
// rule every tree shape, width and traversal order (and the brute-force loop) picks the same
// one, so changing the BVH never changes a pixel.
#include <bit>
#include <cstdint>

namespace farm {

// The exclusive limit that keeps a query looking up to and including a hit at t: the next float
// up. A hit's t is positive and finite (intersect_triangle takes t > its epsilon), so that is
// the next bit pattern, with no call into libm on the hot path.
inline float limit_through(float t) { return std::bit_cast<float>(std::bit_cast<std::uint32_t>(t) + 1u); }

// Whether a hit at (t, id) replaces the best so far at (best_t, best_id), id being the object's
// or, within one object, the triangle's index.
inline bool nearer_hit(float t, std::uint32_t id, float best_t, std::uint32_t best_id) {
  return t < best_t || (t == best_t && id < best_id);
}

}  // namespace farm
