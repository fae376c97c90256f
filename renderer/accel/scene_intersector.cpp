#include "renderer/accel/scene_intersector.h"

namespace farm {

unsigned SceneIntersector::find_closest_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  unsigned found = 0;
  for (lanes &= 0xFFu; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    if (find_closest(rays[i], hits[i])) found |= 1u << i;
  }
  return found;
}

unsigned SceneIntersector::closest_hit_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  unsigned found = 0;
  for (lanes &= 0xFFu; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    if (closest_hit(rays[i], hits[i])) found |= 1u << i;
  }
  return found;
}

}  // namespace farm
