#include "server/bench/bench_scenes.h"

#include "renderer/scene/transform.h"
#include "renderer/util/input_error.h"

namespace farm::bench {

std::filesystem::path default_cow_path() { return "../shared/assets/dae/cow.dae"; }

namespace {

SceneObject instance_of(const std::shared_ptr<const Model>& model, const glm::vec3& at,
                        float degrees, const std::string& name) {
  SceneObject object;
  object.name = name;
  object.model = model;
  object.materials = model->materials;
  ObjectTransform t;
  t.translate = at;
  t.rotate_degrees = degrees;
  object.model_to_world = t.matrix();
  return object;
}

}  // namespace

Scene single_cow(const std::shared_ptr<const Model>& cow) {
  Scene scene;
  scene.objects.push_back(instance_of(cow, glm::vec3(0.0f), 0.0f, "cow"));
  scene.camera.position = {2, 2, 2};
  scene.lights.push_back(Light{Light::Kind::Point, {2, 2, 2}, {}, glm::vec3(10.0f)});
  return scene;
}

Scene cow_grid(const std::shared_ptr<const Model>& cow, int side) {
  Scene scene;
  // The cow is about 0.8 wide (x) and 1.5 long (z); spacing leaves a little room between them.
  const float dx = 1.0f, dz = 1.7f;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const glm::vec3 at{(static_cast<float>(i) - 0.5f * static_cast<float>(side - 1)) * dx, 0.0f,
                         (static_cast<float>(j) - 0.5f * static_cast<float>(side - 1)) * dz};
      scene.objects.push_back(instance_of(cow, at, static_cast<float>((i * 37 + j * 11) % 360),
                                          "cow_" + std::to_string(j * side + i)));
    }
  }
  const float extent = static_cast<float>(side) * dz;
  scene.camera.position = {0.0f, 0.75f * extent, 0.95f * extent};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  scene.camera.far = 4.0f * extent;
  scene.lights.push_back(Light{Light::Kind::Point, {0.0f, extent, 0.3f * extent},
                               {}, glm::vec3(extent * extent)});
  return scene;
}

Scene cbbunny_area_lit(Model cbbunny) {
  bool lamp = false;
  for (Material& m : cbbunny.materials) {
    if (m.name == "light") {
      m.emission = glm::vec3(12.0f);
      lamp = true;
    }
  }
  if (!lamp) throw InputError("CBbunny: no material named 'light' to make the lamp of");
  Scene scene;
  if (!cbbunny.cameras.empty()) scene.camera = cbbunny.cameras.front();
  const auto model = std::make_shared<const Model>(std::move(cbbunny));
  scene.objects.push_back(instance_of(model, glm::vec3(0.0f), 0.0f, "CBbunny"));
  scene.background = glm::vec3(0.0f);
  return scene;
}

}  // namespace farm::bench
