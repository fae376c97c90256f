#pragma once
// Coverage on a fixed-point grid. Screen positions are snapped to 1/256 pixel and edge functions
// are evaluated exactly in 64-bit integers, so the fill rule decides every sample that lies on a
// shared edge the same way for both triangles: no cracks, no double hits, and no dependence on
// where a tile starts.
#include <cmath>
#include <cstdint>
#include <glm/vec3.hpp>

namespace farm::raster {

inline constexpr int kSubpixelBits = 8;
inline constexpr std::int64_t kSubpixelScale = std::int64_t{1} << kSubpixelBits;

struct FixedPoint {
  std::int64_t x, y;  // trivial, so vertex arrays holding it can start uninitialized
};

// Rounds half away from zero, as std::llround, without its call (one per vertex coordinate of
// every frame): a float times 256 is exact in a double, and so is adding one half while its
// magnitude is below 2^52, so truncating that sum is llround's answer. Beyond (and for NaN),
// llround itself.
inline std::int64_t to_fixed(float pixels) {
  const double scaled = static_cast<double>(pixels) * static_cast<double>(kSubpixelScale);
  if (!(std::fabs(scaled) < 0x1p52)) return std::llround(scaled);
  return static_cast<std::int64_t>(scaled + (scaled < 0.0 ? -0.5 : 0.5));
}

// Twice the signed area of (a, b, p). With y pointing down the image, it is positive when p lies
// on the inner side of a triangle whose vertices a, b, c give edge_function(a, b, c) > 0.
inline std::int64_t edge_function(const FixedPoint& a, const FixedPoint& b, const FixedPoint& p) {
  return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Top-left rule for positively oriented triangles in y-down screen space: a sample exactly on an
// edge belongs to the triangle only if that edge is a top edge (horizontal, interior below) or a
// left edge (going up the screen). For any edge direction d exactly one of d and -d qualifies,
// which is what makes shared edges watertight.
inline bool is_top_left(const FixedPoint& a, const FixedPoint& b) {
  const std::int64_t dx = b.x - a.x, dy = b.y - a.y;
  return dy < 0 || (dy == 0 && dx > 0);
}

// Value to add to an edge function so that `>= 0` means covered under the fill rule.
inline std::int64_t fill_rule_bias(const FixedPoint& a, const FixedPoint& b) {
  return is_top_left(a, b) ? 0 : -1;
}

// The first pixel whose sample (pixel * kSubpixelScale + offset) lies at or after `lo`, and the
// last whose sample lies at or before `hi` (fixed-point, either sign).
// (C++20 defines >> of a negative number as an arithmetic shift, i.e. floor division.)
inline int first_sample_pixel(std::int64_t lo, std::int64_t offset) {
  return static_cast<int>((lo - offset + kSubpixelScale - 1) >> kSubpixelBits);
}
inline int last_sample_pixel(std::int64_t hi, std::int64_t offset) {
  return static_cast<int>((hi - offset) >> kSubpixelBits);
}

// Screen-space barycentric weights of p in triangle (a, b, c), in the order (a, b, c).
inline glm::dvec3 barycentric(const FixedPoint& a, const FixedPoint& b, const FixedPoint& c,
                              const FixedPoint& p) {
  const double area = static_cast<double>(edge_function(a, b, c));
  return {static_cast<double>(edge_function(b, c, p)) / area,
          static_cast<double>(edge_function(c, a, p)) / area,
          static_cast<double>(edge_function(a, b, p)) / area};
}

}  // namespace farm::raster
