#pragma once
// A scene made ready for rendering: everything that depends only on the scene (world matrices,
// normal matrices, flattened triangles per model) computed once per job per process and shared
// by all tiles; engines cache their own derived structures (BVHs, frame set-up) in frame_cache().
// The models are flattened when a ray engine first asks for objects(), not before: the
// rasterizer reads the meshes themselves (placements()), and a raster job pays nothing for them.
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <vector>

#include <atomic>
#include <memory>
#include <mutex>

#include "renderer/accel/model_geometry.h"
#include "renderer/accel/model_triangles.h"
#include "renderer/scene/scene.h"
#include "renderer/util/frame_cache.h"

namespace farm {

struct PreparedObject {
  const SceneObject* source = nullptr;
  const ModelTriangles* triangles = nullptr;  // shared by every object of the same model (objects())
  glm::mat4 model_to_world{1.0f};
  glm::mat4 world_to_model{1.0f};
  glm::mat3 normal_to_world{1.0f};  // inverse transpose of the linear part
  // normal_to_world is the identity (an object placed without rotation or scale): its hits'
  // normals are the model's, no product and no second normalisation.
  bool normals_untransformed = false;
};

class PreparedScene {
 public:
  // `geometry`: what other frames of the job built already (their models' triangles and
  // BVHs), shared; null: this scene's own.
  explicit PreparedScene(Scene scene, std::shared_ptr<ModelGeometry> geometry = nullptr);
  PreparedScene(const PreparedScene&) = delete;
  PreparedScene& operator=(const PreparedScene&) = delete;

  const Scene& scene() const { return scene_; }
  // Every object with its model's triangles (flattened for the whole scene on the first call,
  // from any thread): what the ray engines read.
  // Inline, a load and a branch once flattened: complete_surface_hit asks it at every hit, and
  // std::call_once alone cost 35 instructions a call (TLS writes and a pthread_once call).
  const std::vector<PreparedObject>& objects() const {
    if (!flattened_.load(std::memory_order_acquire)) flatten();
    return objects_;
  }
  // The same objects with `triangles` null until objects() has been called: their sources and
  // transforms, for an engine that never reads the triangles (the rasterizer).
  const std::vector<PreparedObject>& placements() const { return objects_; }
  std::size_t triangle_count() const { return scene_.triangle_count(); }
  // The world box of every object's model box carried over by its placement (geometry/aabb.h's
  // transformed); empty for a scene without triangles. Flattens the models (objects()).
  AABB world_bounds() const;

  // The models' triangles and bottom-level structures, shared with the job's other frames.
  ModelGeometry& geometry() const { return *geometry_; }
  const std::shared_ptr<ModelGeometry>& shared_geometry() const { return geometry_; }

  // Engines keep per-frame set-up here; it is derived data, so a const scene may fill it.
  FrameCache& frame_cache() const { return frame_cache_; }

 private:
  Scene scene_;
  void flatten() const;  // fills every object's `triangles`, once

  mutable std::vector<PreparedObject> objects_;  // `triangles` filled once, by objects()
  mutable std::once_flag flatten_once_;
  mutable std::atomic<bool> flattened_{false};  // set, with release, when flatten_once_ is done
  std::shared_ptr<ModelGeometry> geometry_;
  mutable FrameCache frame_cache_;
};

}  // namespace farm
