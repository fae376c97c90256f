// Our BVHs against Embree on the lab's models and an instanced scene: a million rays each (half
// primary, half from inside the scene in every direction).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/vec4.hpp>
#include <stdexcept>
#include <string>

#include "renderer/accel/accel_validation.h"
#include "renderer/accel/embree_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/scene/model.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

#ifdef NDEBUG
constexpr std::uint64_t kRays = 1'000'000;
#else
constexpr std::uint64_t kRays = 100'000;  // unoptimised traversal is ~20x slower
#endif

// A camera that frames the whole scene from an oblique direction.
Camera framing(const AABB& bounds) {
  Camera camera;
  const glm::vec3 centre = bounds.center();
  const float radius = 0.5f * glm::length(bounds.extent());
  camera.target = centre;
  camera.position = centre + radius * 2.6f * glm::normalize(glm::vec3(0.6f, 0.4f, 1.0f));
  camera.fov_y_degrees = 45.0f;
  return camera;
}

void expect_agreement(Scene scene, const char* what) {
  AABB bounds;
  for (const SceneObject& o : scene.objects) {
    for (const Mesh& mesh : o.model->meshes) {
      for (const glm::vec3& p : mesh.positions) bounds.grow(glm::vec3(o.model_to_world * glm::vec4(p, 1.0f)));
    }
  }
  scene.camera = framing(bounds);
  const PreparedScene prepared(std::move(scene));
  RenderSettings settings;
  settings.width = 320;
  settings.height = 240;
  settings.seed = 11;
  const auto embree = build_embree_intersector(prepared);
  for (AccelKind accel : {AccelKind::Bvh, AccelKind::BvhMedian}) {
    const std::unique_ptr<SceneIntersector> ours = build_scene_intersector(prepared, accel);
    const AccelValidation v = validate_accel(prepared, settings, *ours, *embree, kRays);
    std::printf("%s, %s: %s\n", what, std::string(to_string(accel)).c_str(), v.summary().c_str());
    const double allowed = 1e-5 * static_cast<double>(kRays);  // 99.999% agreement
    EXPECT_LE(static_cast<double>(v.hit_miss_disagreements), allowed) << what << " " << v.summary();
    EXPECT_LE(static_cast<double>(v.triangle_disagreements), allowed) << what << " " << v.summary();
    EXPECT_LE(v.max_relative_t_difference, 1e-4) << what << " " << v.summary();
  }
}

void expect_agreement_on_lab_model(const char* relative) {
  const fs::path file = fs::path(FARM_SHARED_ASSETS) / relative;
  if (!fs::exists(file)) GTEST_SKIP() << file << " is not here";
  Scene scene;
  scene.objects.push_back(test::object_of(load_model(file)));
  expect_agreement(std::move(scene), relative);
}

TEST(EmbreeAgreement, CowHitsMatchEmbree) { expect_agreement_on_lab_model("dae/cow.dae"); }
TEST(EmbreeAgreement, BunnyHitsMatchEmbree) { expect_agreement_on_lab_model("dae/bunny.dae"); }
TEST(EmbreeAgreement, CornellBunnyHitsMatchEmbree) { expect_agreement_on_lab_model("dae/CBbunny.dae"); }

TEST(EmbreeAgreement, InstancesWithRotationNonUniformScaleAndMirroringMatchEmbree) {
  auto placed = [](glm::vec3 t, float degrees, glm::vec3 axis, glm::vec3 s) {
    return glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), t), glm::radians(degrees),
                                  glm::normalize(axis)), s);
  };
  Scene scene;
  SceneObject sphere = test::object_of(test::make_sphere(48, 64), placed({0, 0, 0}, 0, {0, 1, 0}, {1, 1, 1}));
  scene.objects.push_back(sphere);
  sphere.model_to_world = placed({2.5f, 0.3f, 0}, 35, {1, 0, 1}, {0.4f, 1.6f, 0.9f});
  scene.objects.push_back(sphere);
  sphere.model_to_world = placed({-2.2f, 0.5f, 0.8f}, -60, {0, 1, 1}, {-0.7f, 0.5f, 1.1f});
  scene.objects.push_back(sphere);
  scene.objects.push_back(test::object_of(test::make_box({-1, -1, -1}, {1, 1, 1}),
                                          placed({0, 1.8f, -1.5f}, 20, {1, 1, 1}, {1.5f, 0.3f, 0.6f})));
  scene.objects.push_back(test::object_of(test::make_grid(40),
                                          placed({0, -1.2f, 0}, -90, {1, 0, 0}, {4, -3, 1})));
  expect_agreement(std::move(scene), "instanced scene");
}

}  // namespace
}  // namespace farm
