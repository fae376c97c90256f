#pragma once
// Our SceneIntersector: a top-level BVH over the objects' world-space boxes, whose leaves carry
// the ray into each object's model space and query the model's MeshAccel. Objects of one model
// share that MeshAccel (100 cows, one BVH). build_scene_intersector returns one of these for
// every accel but Embree; build it directly to reach the structures behind it (--show-bvh).
#include <cstdint>
#include <functional>
#include <glm/mat4x4.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "renderer/accel/mesh_accel.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/geometry/bvh.h"

namespace farm {

// One BVH node box for drawing: its 8 corners in world space are to_world * corner(bounds).
struct BvhBox {
  AABB bounds;            // top level: world space; bottom level: the object's model space
  glm::mat4 to_world{1.0f};  // identity at the top level, the object's model_to_world below
  int level = 0;          // depth inside its own tree (each tree's root is 0)
  std::int64_t object = -1;  // the object a bottom-level box belongs to; -1 for the top level
};

class InstanceIntersector final : public SceneIntersector {
 public:
  // An instance's top-level box is the box of its model's vertices carried to the world, the
  // tightest there is, while all instances of that model together carry at most this many
  // vertices (every top-level build pays for them, each frame that moves an object: the cow
  // placed 324 times, 949,320 vertices, took 1.4 ms on one thread, 361 times with upper boxes
  // 0.23 ms); beyond, it is made of the model's upper BVH boxes, 32 corners an instance. On the
  // 100-cow grid (each cow turned by its own angle) the rays of `farm bench rt` entered 0.513
  // instances a primary ray with the model box's corners, 0.471 with the upper boxes two levels
  // down (0.451 four down) and 0.410 with the vertices (incoherent rays: 1.743 and 1.455).
  static constexpr std::size_t kExactBoxVertices = std::size_t{1} << 20;

  // `accel` must be Naive, BvhMedian or Bvh; `scene` must outlive the intersector. With Naive
  // every triangle of every object is tested (no top-level tree either), as the lab's `naive`.
  // The builds poll `cancel`: throws RenderStopped when it asks.
  InstanceIntersector(const PreparedScene& scene, AccelKind accel,
                      const CancelFlag& cancel = CancelFlag::never());

  bool closest_hit(const Ray& ray, SurfaceHit& hit, TraversalStats* stats = nullptr) const override;
  bool find_closest(const Ray& ray, SurfaceHit& hit, TraversalStats* stats = nullptr) const override;
  unsigned find_closest_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const override;
  unsigned closest_hit_packet(const Ray* rays, unsigned lanes, SurfaceHit* hits) const override;
  bool occluded(const Ray& ray, TraversalStats* stats = nullptr) const override;
  unsigned occluded_packet(const Ray* rays, unsigned lanes) const override;

  // Structures built: one MeshAccel per distinct model.
  std::size_t mesh_accel_count() const { return mesh_accels_.size(); }
  const MeshAccel& mesh_accel_of(std::uint32_t object) const { return *object_accel_[object]; }
  const Bvh* top_level() const { return top_ ? &*top_ : nullptr; }  // null for Naive

  // Calls visit for every top-level node of level <= max_level, then, for every object, every
  // node of its model's BVH of level <= max_level (an object's boxes repeat per instance, each
  // with that instance's transform). Nothing for Naive.
  void visit_bvh_boxes(int max_level, const std::function<void(const BvhBox&)>& visit) const;

 private:
  // What testing one object takes, kept together in the order the top level's leaves list their
  // objects (Bvh::order(); object order without a top level): a leaf's object is one read away,
  // not an index into order(), then into the scene's objects and object_accel_.
  struct Placement {
    glm::mat4 world_to_model{1.0f};
    const MeshAccel* accel = nullptr;
    std::uint32_t object = 0;
  };

  // Nearest hit over a placed object, the world ray carried into its model space.
  static bool closest_in(const Placement& placement, const Ray& world_ray, float t_max, TriangleHit& hit,
                         TraversalStats* stats);
  static bool any_in(const Placement& placement, const Ray& world_ray, TraversalStats* stats);

  const PreparedScene& scene_;
  // One per distinct ModelTriangles, from the scene's ModelGeometry: built by the first frame
  // of a job that needs it, shared by the rest.
  std::vector<std::shared_ptr<const MeshAccel>> mesh_accels_;
  std::vector<const MeshAccel*> object_accel_;           // per object
  std::optional<Bvh> top_;
  std::vector<Placement> placements_;  // per entry of top_->order(), or per object without top_
  // A scene of one object is queried without the top level (a tree of one leaf), and without
  // carrying the ray into model space when its transform is the identity.
  bool one_object_ = false;
  bool one_object_untransformed_ = false;
};

std::unique_ptr<InstanceIntersector> build_instance_intersector(
    const PreparedScene& scene, AccelKind accel, const CancelFlag& cancel = CancelFlag::never());

}  // namespace farm
