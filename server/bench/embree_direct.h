#pragma once
// Embree as its users call it, for `farm bench rt`'s anchor (issue #37): one scene of world-space
// triangle meshes (every object's triangles moved by its transform, no instance level), built with
// Embree's default quality, and rtcIntersect1 / rtcOccluded1 on each ray (rtcIntersect8 /
// rtcOccluded8 on packets of 8), nothing computed from the hit. The farm's EmbreeIntersector (renderer/accel) answers the renderer's questions instead: an
// instance per object and the full surface hit; the bench prints both.
#include <memory>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/geometry/ray.h"

namespace farm {

class EmbreeDirect {
 public:
  explicit EmbreeDirect(const PreparedScene& scene);  // std::runtime_error on Embree's errors
  ~EmbreeDirect();
  EmbreeDirect(const EmbreeDirect&) = delete;
  EmbreeDirect& operator=(const EmbreeDirect&) = delete;

  // Thread-safe, as Embree's queries are.
  bool closest_hit(const Ray& ray) const;
  bool occluded(const Ray& ray) const;
  // rtcIntersect8 on rays[i] for each bit i of `lanes` (8 at most): the lanes hit.
  unsigned closest_hit8(const Ray* rays, unsigned lanes) const;
  // rtcOccluded8 likewise: the lanes blocked.
  unsigned occluded8(const Ray* rays, unsigned lanes) const;

 private:
  struct Handles;
  std::unique_ptr<Handles> handles_;
};

}  // namespace farm
