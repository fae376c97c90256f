#pragma once
// Four triangles against one ray at once, lane by lane the very arithmetic of intersect_triangle
// (triangle_intersect.h): the same products and sums in the same order, no fused multiply-add,
// an exact division. So every lane's t, u and v are the bits the scalar test gives, and a BVH
// that tests its leaves four at a time finds exactly the hits it found one at a time.
#include <cstdint>
#include <glm/vec3.hpp>
#include <immintrin.h>
#include <limits>

#include "renderer/geometry/ray.h"

namespace farm {

// A BVH leaf's triangles, stored axis by axis. Lanes past the leaf's last triangle stay zero:
// their determinant is 0, so they are never hit.
struct alignas(16) Triangle4 {
  float a[3][4] = {};        // corner a
  float e1[3][4] = {};       // b - a
  float e2[3][4] = {};       // c - a
  float edge_scale[4] = {};  // dot(e1, e1) * dot(e2, e2): the determinant test's scale but the ray's part

  void set(int lane, const glm::vec3& corner_a, const glm::vec3& corner_b, const glm::vec3& corner_c) {
    const glm::vec3 edge1 = corner_b - corner_a, edge2 = corner_c - corner_a;
    for (int axis = 0; axis < 3; ++axis) {
      a[axis][lane] = corner_a[axis];
      e1[axis][lane] = edge1[axis];
      e2[axis][lane] = edge2[axis];
    }
    // As glm::dot sums: (x + y) + z.
    const float e1e1 = (edge1.x * edge1.x + edge1.y * edge1.y) + edge1.z * edge1.z;
    const float e2e2 = (edge2.x * edge2.x + edge2.y * edge2.y) + edge2.z * edge2.z;
    edge_scale[lane] = e1e1 * e2e2;
  }
};

// A ray's two values every Triangle4 test reads, one way for the single test and the packet
// test (triangle4_packet.h), which must agree to the bit: the least t a hit may have, max(t_min,
// t_epsilon) as std::max picks it, and dot(d, d) as glm::dot sums it.
inline float triangle_t_lower(const Ray& ray, float t_epsilon) { return ray.t_min < t_epsilon ? t_epsilon : ray.t_min; }
inline float triangle_direction_dot(const Ray& ray) {
  const glm::vec3& d = ray.direction;
  return (d.x * d.x + d.y * d.y) + d.z * d.z;
}

// What one ray brings to every Triangle4 test, worked out once per query.
struct Triangle4Ray {
  __m128 origin[3], direction[3];
  __m128 t_lower;         // max(ray.t_min, t_epsilon): hits must lie beyond it
  __m128 direction_dot;   // dot(d, d)

  explicit Triangle4Ray(const Ray& ray, float t_epsilon = 1e-6f) {
    for (int axis = 0; axis < 3; ++axis) {
      origin[axis] = _mm_set1_ps(ray.origin[axis]);
      direction[axis] = _mm_set1_ps(ray.direction[axis]);
    }
    t_lower = _mm_set1_ps(triangle_t_lower(ray, t_epsilon));
    direction_dot = _mm_set1_ps(triangle_direction_dot(ray));
  }
};

// The lanes hit with t in (t_lower, t_max), as a 4-bit mask; t of the lanes hit (+inf in the
// others), u and v of every lane.
inline int intersect_triangle4(const Triangle4Ray& ray, const Triangle4& tri, float t_max, __m128& t_out,
                               __m128& u_out, __m128& v_out) {
  const __m128 ax = _mm_load_ps(tri.a[0]), ay = _mm_load_ps(tri.a[1]), az = _mm_load_ps(tri.a[2]);
  const __m128 e1x = _mm_load_ps(tri.e1[0]), e1y = _mm_load_ps(tri.e1[1]), e1z = _mm_load_ps(tri.e1[2]);
  const __m128 e2x = _mm_load_ps(tri.e2[0]), e2y = _mm_load_ps(tri.e2[1]), e2z = _mm_load_ps(tri.e2[2]);
  const __m128 dx = ray.direction[0], dy = ray.direction[1], dz = ray.direction[2];
  // p = cross(d, e2), as glm::cross orders its products.
  const __m128 px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(e2y, dz));
  const __m128 py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(e2z, dx));
  const __m128 pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(e2x, dy));
  const __m128 det = _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)), _mm_mul_ps(e1z, pz));
  const __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
  const __m128 sx = _mm_sub_ps(ray.origin[0], ax), sy = _mm_sub_ps(ray.origin[1], ay),
               sz = _mm_sub_ps(ray.origin[2], az);
  const __m128 u =
      _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(sx, px), _mm_mul_ps(sy, py)), _mm_mul_ps(sz, pz)), inv_det);
  // q = cross(s, e1).
  const __m128 qx = _mm_sub_ps(_mm_mul_ps(sy, e1z), _mm_mul_ps(e1y, sz));
  const __m128 qy = _mm_sub_ps(_mm_mul_ps(sz, e1x), _mm_mul_ps(e1z, sx));
  const __m128 qz = _mm_sub_ps(_mm_mul_ps(sx, e1y), _mm_mul_ps(e1x, sy));
  const __m128 v =
      _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)), _mm_mul_ps(dz, qz)), inv_det);
  const __m128 t =
      _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)), _mm_mul_ps(e2z, qz)), inv_det);
  // The scalar test's rejections, each written so that a NaN passes it exactly when it passes
  // there: "not (u < 0)" is cmpnlt, true for NaN, as the scalar `if (u < 0 || ...)` lets it by.
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  __m128 ok = _mm_cmpneq_ps(det, zero);
  ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpnlt_ps(u, zero), _mm_cmpngt_ps(u, one)));
  ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpnlt_ps(v, zero), _mm_cmpngt_ps(_mm_add_ps(u, v), one)));
  ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(t, ray.t_lower), _mm_cmplt_ps(t, _mm_set1_ps(t_max))));
  const __m128 scale2 = _mm_mul_ps(_mm_load_ps(tri.edge_scale), ray.direction_dot);
  ok = _mm_and_ps(ok, _mm_cmpgt_ps(_mm_mul_ps(det, det), _mm_mul_ps(_mm_set1_ps(1e-24f), scale2)));
  t_out = _mm_or_ps(_mm_and_ps(ok, t), _mm_andnot_ps(ok, _mm_set1_ps(std::numeric_limits<float>::infinity())));
  u_out = u;
  v_out = v;
  return _mm_movemask_ps(ok);
}

// Of the lanes in `mask` (not empty), the one of least t (t_out of intersect_triangle4, +inf
// in the lanes missed), and of equals the one of least id: the nearest hit by the same rule
// whichever order the triangles were tested in (ray_hit_order.h).
inline int nearest_lane(int mask, __m128 t, const std::uint32_t* ids) {
  __m128 least = _mm_min_ps(t, _mm_shuffle_ps(t, t, _MM_SHUFFLE(2, 3, 0, 1)));
  least = _mm_min_ps(least, _mm_shuffle_ps(least, least, _MM_SHUFFLE(1, 0, 3, 2)));
  unsigned at_least = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpeq_ps(t, least)) & mask);
  int lane = __builtin_ctz(at_least);
  for (at_least &= at_least - 1; at_least != 0; at_least &= at_least - 1) {  // a tie: rare
    const int other = __builtin_ctz(at_least);
    if (ids[other] < ids[lane]) lane = other;
  }
  return lane;
}

}  // namespace farm
