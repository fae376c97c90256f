#include "renderer/job/scene_builder.h"

#include <fmt/format.h>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec4.hpp>
#include <map>
#include <memory>

#include "renderer/texture/environment_light.h"
#include "renderer/texture/material_textures.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/util/input_error.h"

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

// The animation object `o` (job index i) plays of `model`; null when none.
const ModelAnimation* picked_animation(const Job& job, std::size_t i, const JobObject& o, const Model& model) {
  const ObjectAnimation& a = o.animation;
  const auto fail = [&](const std::string& what) -> void {
    throw InputError(fmt::format("{}: scene.objects[{}].animation: {}", job.path.string(), i, what));
  };
  switch (a.pick) {
    case ObjectAnimation::Pick::Off: return nullptr;
    case ObjectAnimation::Pick::First: return model.animations.empty() ? nullptr : &model.animations.front();
    case ObjectAnimation::Pick::Index:
      if (a.index >= model.animations.size()) {
        fail(fmt::format("'{}' has {} animation(s), no animation {}", o.file_as_written, model.animations.size(), a.index));
      }
      return &model.animations[a.index];
    case ObjectAnimation::Pick::Name: {
      const std::optional<std::size_t> found = find_animation(model, a.name);
      if (!found) {
        std::string names;
        for (const ModelAnimation& m : model.animations) names += (names.empty() ? "'" : ", '") + m.name + "'";
        fail(fmt::format("'{}' has no animation '{}' ({})", o.file_as_written, a.name.substr(0, 64),
                         names.empty() ? "it has none" : "it has " + names));
      }
      return &model.animations[*found];
    }
  }
  return nullptr;
}

}  // namespace

Scene build_scene(const Job& job) { return load_job_scene(job).scene; }

LoadedScene load_job_scene(const Job& job) {
  // A job put together in code may have no asset root, and then each model's own folder is its root.
  LoadedScene loaded{std::make_shared<ModelLibrary>(job.asset_root), {}};
  loaded.scene = build_scene(job, *loaded.models);
  return loaded;
}

Scene build_scene(const Job& job, ModelLibrary& models) {
  Scene scene;
  scene.ambient = job.scene.ambient;
  scene.background = job.scene.background;
  if (const auto& e = job.scene.environment) {
    std::shared_ptr<const Texture> map;
    if (!e->map.empty()) {
      try {
        // Decoded once per process like every texture; 8-bit images hold sRGB colour.
        map = TextureCache::process().get(e->map, TextureColourSpace::Srgb);
      } catch (const InputError& error) {
        throw InputError(fmt::format("{}: scene.environment.map: {}", job.path.string(), error.what()));
      }
    }
    scene.environment = std::make_shared<const EnvironmentLight>(e->radiance, e->intensity, e->rotate_degrees, std::move(map));
  }

  // Objects whose files share a stem get their job index appended, so names stay unique.
  std::map<std::string, int> stem_uses;
  for (const JobObject& o : job.scene.objects) ++stem_uses[o.file.stem().string()];

  std::vector<std::pair<std::shared_ptr<const Model>, glm::mat4>> placed;  // per job object
  for (std::size_t i = 0; i < job.scene.objects.size(); ++i) {
    const JobObject& o = job.scene.objects[i];
    std::shared_ptr<const Model> model;
    try {
      model = models.load(o.file);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: scene.objects[{}].file: {}", job.path.string(), i, e.what()));
    }

    const std::string stem = o.file.stem().string();
    const std::string name = stem_uses[stem] > 1 ? fmt::format("{}_{}", stem, i) : stem;
    const auto add_object = [&](std::shared_ptr<const Model> m, const glm::mat4& model_to_world, std::string n) {
      SceneObject so;
      so.name = std::move(n);
      so.model = std::move(m);
      so.model_to_world = model_to_world;
      so.materials = so.model->materials;
      if (so.materials.empty()) so.materials.emplace_back();  // loaders promise one; be safe
      for (Material& mat : so.materials) o.material.apply_to(mat);
      scene.objects.push_back(std::move(so));
    };
    // A model's cameras and lights follow its object (at the rest pose: animations move meshes).
    placed.emplace_back(model, o.transform.matrix());
    const ModelAnimation* animation = picked_animation(job, i, o, *model);
    if (!animation) {
      add_object(model, o.transform.matrix(), name);
      continue;
    }
    // An animated model is placed node by node: each node's meshes are a part of the model (made
    // once, shared by every frame with its BVH), its object the node's pose at the frame's time
    // on top of the job's transform. Only the top level differs between frames.
    std::map<int, glm::mat4> poses;  // by node; -1: the meshes of no node
    try {
      const std::vector<glm::mat4> rest_to_posed = rest_to_posed_matrices(*model, animation, job.seconds);
      for (const Mesh& mesh : model->meshes) poses.emplace(mesh.node, mesh_rest_to_posed(mesh, rest_to_posed));
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: scene.objects[{}].animation: {}", job.path.string(), i, e.what()));
    }
    for (const auto& [node, pose] : poses) {
      const std::shared_ptr<const Model> part = models.node_part(o.file, node);
      const std::string node_name =
          node >= 0 && !model->nodes[static_cast<std::size_t>(node)].name.empty()
              ? model->nodes[static_cast<std::size_t>(node)].name
              : fmt::format("node{}", node);
      add_object(part, o.transform.matrix() * pose, poses.size() == 1 ? name : fmt::format("{}/{}", name, node_name));
    }
  }

  if (job.scene.camera) {
    scene.camera = *job.scene.camera;
  } else {
    for (const auto& [model, model_to_world] : placed) {
      if (!model->cameras.empty()) {
        scene.camera = place_camera(model->cameras.front(), model_to_world);
        break;
      }
    }
  }

  if (job.scene.lights) {
    scene.lights = *job.scene.lights;  // even an empty list: the job asked for no lights
  } else {
    for (const auto& [model, model_to_world] : placed) {
      for (const Light& l : model->lights) scene.lights.push_back(place_light(l, model_to_world));
    }
  }
  return scene;
}

}  // namespace farm
