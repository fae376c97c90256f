#include "renderer/accel/scene_intersector.h"

namespace farm {
namespace {

// `query(ray, hit)` on each ray of `lanes`: the lanes it says were hit.
template <typename Query>
unsigned ray_by_ray(const Ray* rays, unsigned lanes, SurfaceHit* hits, Query&& query) {
  unsigned found = 0;
  for (lanes &= 0xFFu; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    if (query(rays[i], hits[i])) found |= 1u << i;
  }
  return found;
}

}  // namespace

unsigned SceneIntersector::find_closest_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  return ray_by_ray(rays, lanes, hits, [this](const Ray& ray, SurfaceHit& hit) { return find_closest(ray, hit); });
}

unsigned SceneIntersector::occluded_packet(const Ray* rays, unsigned lanes) const {
  unsigned blocked = 0;
  for (lanes &= 0xFFu; lanes; lanes &= lanes - 1) {
    const int i = __builtin_ctz(lanes);
    if (occluded(rays[i])) blocked |= 1u << i;
  }
  return blocked;
}

unsigned SceneIntersector::closest_hit_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const {
  return ray_by_ray(rays, lanes, hits, [this](const Ray& ray, SurfaceHit& hit) { return closest_hit(ray, hit); });
}

}  // namespace farm
