#include "renderer/accel/prepared_scene.h"

#include <glm/matrix.hpp>

#include "renderer/scene/transform.h"

namespace farm {

PreparedScene::PreparedScene(Scene scene, std::shared_ptr<ModelGeometry> geometry)
    : scene_(std::move(scene)), geometry_(geometry ? std::move(geometry) : std::make_shared<ModelGeometry>()) {
  objects_.reserve(scene_.objects.size());
  for (const SceneObject& object : scene_.objects) {
    const glm::mat3 normal_to_world = normal_matrix(object.model_to_world);
    objects_.push_back({&object, nullptr, object.model_to_world, glm::inverse(object.model_to_world),
                        normal_to_world, normal_to_world == glm::mat3(1.0f)});
  }
}

void PreparedScene::flatten() const {
  std::call_once(flatten_once_, [this] {
    for (PreparedObject& object : objects_) object.triangles = &geometry_->triangles(object.source->model);
    flattened_.store(true, std::memory_order_release);
  });
}

AABB PreparedScene::world_bounds() const {
  AABB world;
  for (const PreparedObject& object : objects()) {
    world.grow(transformed(object.triangles->bounds, object.model_to_world));
  }
  return world;
}

}  // namespace farm
