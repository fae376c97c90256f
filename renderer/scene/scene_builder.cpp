#include "renderer/scene/scene_builder.h"

#include <fmt/format.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec4.hpp>
#include <map>
#include <memory>

#include "renderer/scene/input_error.h"

namespace farm {

namespace {

glm::vec3 transform_point(const glm::mat4& m, const glm::vec3& p) {
  return glm::vec3(m * glm::vec4(p, 1.0f));
}

glm::vec3 transform_direction(const glm::mat4& m, const glm::vec3& d) {
  return glm::normalize(glm::mat3(m) * d);
}

// Cameras and lights in a model file live in its model space, like its meshes, so they follow
// the object's placement.
Camera place_camera(const Camera& c, const glm::mat4& model_to_world) {
  Camera out = c;
  out.position = transform_point(model_to_world, c.position);
  out.target = transform_point(model_to_world, c.target);
  out.up = transform_direction(model_to_world, c.up);
  return out;
}

Light place_light(const Light& l, const glm::mat4& model_to_world) {
  Light out = l;
  out.position = transform_point(model_to_world, l.position);
  out.direction = transform_direction(model_to_world, l.direction);
  return out;
}

}  // namespace

Scene build_scene(const Job& job) {
  // A job put together in code may have no asset root, and then each model's own folder is its root.
  ModelLibrary models(job.asset_root);
  return build_scene(job, models);
}

Scene build_scene(const Job& job, ModelLibrary& models) {
  Scene scene;
  scene.ambient = job.scene.ambient;
  scene.background = job.scene.background;

  // Objects whose files share a stem get their job index appended, so names stay unique.
  std::map<std::string, int> stem_uses;
  for (const JobObject& o : job.scene.objects) ++stem_uses[o.file.stem().string()];

  for (std::size_t i = 0; i < job.scene.objects.size(); ++i) {
    const JobObject& o = job.scene.objects[i];
    std::shared_ptr<const Model> model;
    try {
      model = models.load(o.file);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: scene.objects[{}].file: {}", job.path.string(), i, e.what()));
    }

    SceneObject so;
    const std::string stem = o.file.stem().string();
    so.name = stem_uses[stem] > 1 ? fmt::format("{}_{}", stem, i) : stem;
    so.model = model;
    so.model_to_world = o.transform.matrix();
    so.materials = model->materials;
    if (so.materials.empty()) so.materials.emplace_back();  // loaders promise one; be safe
    for (Material& m : so.materials) o.material.apply_to(m);
    scene.objects.push_back(std::move(so));
  }

  if (job.scene.camera) {
    scene.camera = *job.scene.camera;
  } else {
    for (const SceneObject& so : scene.objects) {
      if (!so.model->cameras.empty()) {
        scene.camera = place_camera(so.model->cameras.front(), so.model_to_world);
        break;
      }
    }
  }

  if (job.scene.lights) {
    scene.lights = *job.scene.lights;  // even an empty list: the job asked for no lights
  } else {
    for (const SceneObject& so : scene.objects) {
      for (const Light& l : so.model->lights) scene.lights.push_back(place_light(l, so.model_to_world));
    }
  }
  return scene;
}

}  // namespace farm
