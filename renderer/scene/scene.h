#pragma once
// The world an engine renders: model instances with their transforms and materials, lights, one
// camera. Built from a job by build_scene (scene_builder.h).
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <string>
#include <vector>

#include "renderer/scene/camera.h"
#include "renderer/scene/light.h"
#include "renderer/scene/material.h"
#include "renderer/scene/model.h"

namespace farm {

class EnvironmentLight;  // renderer/texture/environment_light.h

struct SceneObject {
  std::string name;
  std::shared_ptr<const Model> model;
  glm::mat4 model_to_world{1.0f};
  std::vector<Material> materials;  // the model's materials with the job's override applied
};

struct Scene {
  std::vector<SceneObject> objects;
  std::vector<Light> lights;
  Camera camera;
  glm::vec3 ambient{0.1f};
  glm::vec3 background{100.0f / 255.0f};
  // Light from all around, which then stands for both values above (background_radiance and
  // ambient_light in environment_light.h read whichever the scene has); null: none.
  std::shared_ptr<const EnvironmentLight> environment;

  std::size_t triangle_count() const;
};

}  // namespace farm
