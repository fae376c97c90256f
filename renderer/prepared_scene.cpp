#include "renderer/prepared_scene.h"

#include <glm/matrix.hpp>
#include <map>

#include "renderer/scene/transform.h"

namespace farm {

PreparedScene::PreparedScene(Scene scene) : scene_(std::move(scene)) {
  std::map<const Model*, const ModelTriangles*> triangles_of;
  objects_.reserve(scene_.objects.size());
  for (const SceneObject& object : scene_.objects) {
    const ModelTriangles*& triangles = triangles_of[object.model.get()];
    if (!triangles) {
      model_triangles_.push_back(std::make_unique<ModelTriangles>(*object.model));
      triangles = model_triangles_.back().get();
    }
    objects_.push_back({&object, triangles, object.model_to_world,
                        glm::inverse(object.model_to_world), normal_matrix(object.model_to_world)});
  }
}

}  // namespace farm
