#pragma once
// A farm Ray as Embree's, and Embree's single-ray queries spelled once for Embree 3 and 4:
// what the renderer's Embree intersector and `farm bench rt`'s direct anchor both call. Included
// only by code that links Embree itself. Embree 4 (Ubuntu 24.04) renamed the header and dropped
// the intersect context argument.
#if __has_include(<embree4/rtcore.h>)
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <algorithm>
#include <limits>

#include "renderer/geometry/ray.h"

namespace farm {

inline void to_embree(const Ray& ray, RTCRay& out) {
  out.org_x = ray.origin.x;
  out.org_y = ray.origin.y;
  out.org_z = ray.origin.z;
  out.dir_x = ray.direction.x;
  out.dir_y = ray.direction.y;
  out.dir_z = ray.direction.z;
  // Embree requires the segment to start at or after the origin.
  out.tnear = std::max(ray.t_min, 0.0f);
  out.tfar = ray.t_max;
  out.time = 0.0f;
  out.mask = ~0u;
  out.id = 0;
  out.flags = 0;
}

// rtcIntersect1 on `ray`, the hit cleared first: afterwards query.hit.geomID is
// RTC_INVALID_GEOMETRY_ID on a miss.
inline void embree_intersect1(RTCScene scene, const Ray& ray, RTCRayHit& query) {
  to_embree(ray, query.ray);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
#if RTC_VERSION_MAJOR >= 4
  rtcIntersect1(scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(scene, &context, &query);
#endif
}

// rtcOccluded1 on `ray`: whether anything lies on its segment (Embree sets tfar to -inf then).
inline bool embree_occluded1(RTCScene scene, const Ray& ray) {
  RTCRay query;
  to_embree(ray, query);
#if RTC_VERSION_MAJOR >= 4
  rtcOccluded1(scene, &query);
#else
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1(scene, &context, &query);
#endif
  return query.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace farm
