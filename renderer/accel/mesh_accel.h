#pragma once
// Ray queries against one model's triangles in model space (a bottom-level structure). One
// instance serves every object that uses the model. Implementations: every triangle (`naive`),
// and BVHs split at the median or by the surface area heuristic (bvh.h).
#include <cstdint>
#include <memory>

#include "renderer/accel/model_triangles.h"
#include "renderer/geometry/ray.h"
#include "renderer/geometry/traversal_stats.h"
#include "renderer/geometry/triangle_intersect.h"  // TriangleHit
#include "renderer/geometry/accel_kind.h"
#include "renderer/util/cancel_flag.h"

namespace farm {

class Bvh;

class MeshAccel {
 public:
  virtual ~MeshAccel() = default;
  // Nearest hit with t in (ray.t_min, ray.t_max); `stats` (optional) counts the work.
  virtual bool closest_hit(const Ray& ray, TriangleHit& hit, TraversalStats* stats) const = 0;
  // Whether anything is hit with t in (ray.t_min, ray.t_max).
  virtual bool any_hit(const Ray& ray, TraversalStats* stats) const = 0;
  // closest_hit for up to 8 rays at once (rays[i], t_max[i] for each bit i of `lanes`; t_max an
  // array of 8, standing for each ray's own bound): the same hit per ray, bit for bit. Returns the lanes hit, and
  // lowers t_max[i] past each hit (ray_hit_order.h's limit_through). This one asks closest_hit
  // ray by ray; a BVH walks them together (Bvh::closest_packet).
  virtual unsigned closest_hit_packet(const Ray* rays, unsigned lanes, float* t_max, TriangleHit* hits) const;
  // any_hit for up to 8 rays at once (rays[i] for each bit i of `lanes`): returns the lanes hit,
  // each ray's answer any_hit's. This one asks any_hit ray by ray; a BVH walks them together
  // (Bvh::any_packet).
  virtual unsigned any_hit_packet(const Ray* rays, unsigned lanes) const;
  // The BVH behind it, for drawing its boxes; null for `naive`.
  virtual const Bvh* bvh() const { return nullptr; }
};

// `accel` must be Naive, BvhMedian or Bvh (Embree works on whole scenes: embree_intersector.h).
// `triangles` must outlive the result.
// Polls `cancel` during the build: throws RenderStopped when it asks.
std::unique_ptr<MeshAccel> build_mesh_accel(const ModelTriangles& triangles, AccelKind accel,
                                            const CancelFlag& cancel = CancelFlag::never());

}  // namespace farm
