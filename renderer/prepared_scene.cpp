#include "renderer/prepared_scene.h"

#include "renderer/scene/transform.h"

namespace farm {

PreparedScene::PreparedScene(Scene scene) : scene_(std::move(scene)) {
  objects_.reserve(scene_.objects.size());
  for (const SceneObject& object : scene_.objects) {
    objects_.push_back({&object, object.model_to_world, normal_matrix(object.model_to_world)});
  }
}

}  // namespace farm
