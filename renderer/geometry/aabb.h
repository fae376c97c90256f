#pragma once
#include <glm/common.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <limits>

namespace farm {

// Axis-aligned box; an empty box has min > max so that growing it by any point is correct.
// What every slab test multiplies its exit distances by (or its reciprocal, once per ray): a few
// ulps, pbrt's 1 + 2 gamma(3), so that rounding never culls a ray the triangle test hits right on
// a box's boundary. One constant, since the single and packet traversals must round alike.
inline constexpr float kSlabExitWiden = 1.0f + 2.0f * (3.0f * std::numeric_limits<float>::epsilon() * 0.5f) /
                                                   (1.0f - 3.0f * std::numeric_limits<float>::epsilon() * 0.5f);

struct AABB {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};

  bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
  void grow(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void grow(const AABB& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  glm::vec3 extent() const { return max - min; }
  glm::vec3 center() const { return 0.5f * (min + max); }
  // Half the surface area: all the surface area heuristic needs (it only compares ratios).
  float half_area() const {
    if (empty()) return 0.0f;
    const glm::vec3 e = extent();
    return e.x * e.y + e.y * e.z + e.z * e.x;
  }
  bool contains(const AABB& b) const {
    return b.empty() || (min.x <= b.min.x && min.y <= b.min.y && min.z <= b.min.z &&
                         max.x >= b.max.x && max.y >= b.max.y && max.z >= b.max.z);
  }

  // Slab test against the closed box: whether the ray origin + t*d meets it for some t in
  // [t_min, t_max]; t_entry is then the first such t. inv_dir = 1/d per component, so a zero
  // component gives +-inf. A ray lying exactly in a slab's plane (d = 0 there) gives
  // 0 * inf = NaN for that plane; the comparisons below are written so a NaN never replaces
  // the running interval, which treats the ray as inside that slab (the box is closed). Off
  // the plane, d = 0 gives -inf..+inf inside the slab and an empty +-inf interval outside it.
  bool intersect(const glm::vec3& origin, const glm::vec3& inv_dir, float t_min, float t_max,
                 float& t_entry) const {
    // The far distances are widened (kSlabExitWiden) so a ray that the triangle test hits right
    // on the box's boundary is never culled by rounding here.
    float t0 = t_min, t1 = t_max;
    for (int a = 0; a < 3; ++a) {
      // Picking the planes by the sign of inv_dir keeps near <= far without a swap, including
      // for -0.0 directions (inv_dir = -inf).
      const bool negative = inv_dir[a] < 0.0f;
      const float near_plane = negative ? max[a] : min[a];
      const float far_plane = negative ? min[a] : max[a];
      const float t_near = (near_plane - origin[a]) * inv_dir[a];
      const float t_far = (far_plane - origin[a]) * inv_dir[a] * kSlabExitWiden;
      // Comparisons are false for NaN, which leaves t0/t1 unchanged.
      if (t_near > t0) t0 = t_near;
      if (t_far < t1) t1 = t_far;
    }
    t_entry = t0;
    return t0 <= t1;
  }
};

// The box that holds `box` carried by the affine map `to`: the box of its eight corners carried
// over (empty for an empty box). What an object's model-space box is in the world.
inline AABB transformed(const AABB& box, const glm::mat4& to) {
  AABB out;
  if (box.empty()) return out;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::vec3 p{(corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
                      (corner & 4) ? box.max.z : box.min.z};
    out.grow(glm::vec3(to * glm::vec4(p, 1.0f)));
  }
  return out;
}

}  // namespace farm
