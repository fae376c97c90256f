#pragma once
// A leaf's Triangle4 against a packet of up to 8 rays at once, a lane per ray (the transpose of
// intersect_triangle4, where a lane is a triangle): each ray's lane does, triangle by triangle,
// the very operations intersect_triangle4 does in that triangle's lane, so t, u and v come out
// bit for bit, and of a ray's hits the nearest is kept by the same rule as nearest_lane (least
// t, then least id). What a packet's rays do at a leaf most of them meet (docs/architecture.md
// 8.6, "Packets"): four 8-wide tests instead of eight 4-wide ones.
#include <cstdint>

#include "renderer/geometry/ray.h"
#include "renderer/geometry/triangle4.h"

namespace farm {

// A packet's rays as every leaf test reads them, lane by lane what Triangle4Ray holds.
struct alignas(32) Triangle4PacketRays {
  float origin[3][8], direction[3][8];
  float t_lower[8], direction_dot[8];
  float ray_t_max[8];  // the rays' own t_max: any hit's bounds (the closest hit keeps its own)

  // Every lane zero, for set() to fill lane by lane.
  Triangle4PacketRays() : origin{}, direction{}, t_lower{}, direction_dot{}, ray_t_max{} {}
  // rays[i] for each bit i of `lanes`, as set() makes each, zero in the other lanes: the whole
  // packet at once (ray_packet.h). Needs AVX2 (the caller asks traversal_isa() first).
  __attribute__((target("avx2"))) Triangle4PacketRays(const Ray* rays, unsigned lanes, float t_epsilon = 1e-6f);

  void set(int lane, const Ray& ray, float t_epsilon = 1e-6f) {
    for (int axis = 0; axis < 3; ++axis) {
      origin[axis][lane] = ray.origin[axis];
      direction[axis][lane] = ray.direction[axis];
    }
    t_lower[lane] = triangle_t_lower(ray, t_epsilon);
    direction_dot[lane] = triangle_direction_dot(ray);
    ray_t_max[lane] = ray.t_max;
  }
};

// Each ray's nearest hit in the leaf.
struct alignas(32) Triangle4PacketHits {
  float t[8], u[8], v[8];
  std::uint32_t id[8];
};

// For each ray of `lanes`: its nearest hit among the leaf's first `count` triangles (ids[k] the
// id of triangle k) with t in (t_lower, t_max[lane]), as intersect_triangle4 and nearest_lane
// find it. Returns the lanes hit; `hits` holds their t, u, v and id. Needs AVX2 (the caller
// asks traversal_isa() first).
unsigned intersect_triangle4_packet(const Triangle4PacketRays& rays, const Triangle4& tri, int count,
                                    const std::uint32_t* ids, const float* t_max, unsigned lanes,
                                    Triangle4PacketHits& hits);

}  // namespace farm
