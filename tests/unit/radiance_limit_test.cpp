// One rule for extreme light (issue #32, renderer/scene/radiance_limit.h): whatever a scene's
// lights, every engine writes finite pixels, at most kMaxRadiance a channel, the same in process
// and on the farm; and a job file that names light beyond the bound is refused with its key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "renderer/job/job.h"
#include "renderer/scene/radiance_limit.h"
#include "renderer/util/input_error.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

// Beside the example jobs, whose model the test jobs name.
const std::filesystem::path kJobPath = std::filesystem::path(FARM_SOURCE_DIR) / "jobs" / "job.json";

class RadianceLimit : public ::testing::TestWithParam<EngineKind> {};

// A white quad facing the camera under a light of 3e38, which a model file's light may carry
// (only finiteness is asked of it): its irradiance overflows a float to +inf at the quad.
TEST_P(RadianceLimit, ALightOfThreeE38RendersFinitePixelsAtTheBound) {
  Scene scene;
  Material white;
  white.diffuse = glm::vec3(0.8f);
  scene.objects.push_back(test::object_of(test::make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}),
                                          glm::mat4(1.0f), white));
  Light light;
  light.kind = Light::Kind::Point;
  light.position = {0, 0, 0.5f};
  light.intensity = glm::vec3(3e38f);
  scene.lights.push_back(light);
  scene.camera.position = {0, 0, 3};
  scene.camera.target = {0, 0, 0};
  const PreparedScene prepared(std::move(scene));
  RenderSettings settings = test::raster_settings(16, 16);
  settings.engine = GetParam();
  settings.spp = GetParam() == EngineKind::Path ? 4 : 1;
  const TileBuffer film = test::render_full(prepared, settings);
  int at_bound = 0;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      const glm::vec4 p = film.rgba(x, y);
      for (int c = 0; c < 4; ++c) ASSERT_TRUE(std::isfinite(p[c])) << "pixel " << x << ", " << y << " channel " << c;
      ASSERT_LE(p.x, kMaxRadiance);
      if (p.x == kMaxRadiance) ++at_bound;
    }
  }
  // Raster and Whitted light the quad directly; the path tracer sees a point light through its
  // next-event estimation the same way.
  EXPECT_GT(at_bound, 0) << "no pixel reached the bound: the light was not extreme here";
}

INSTANTIATE_TEST_SUITE_P(EveryEngine, RadianceLimit,
                         ::testing::Values(EngineKind::Raster, EngineKind::Whitted, EngineKind::Path),
                         [](const auto& p) { return std::string(to_string(p.param)); });

// The job file holds its light and colours to the bound, naming the key and the bound.
TEST(RadianceLimitJob, ALightColourOrEmissionBeyondTheBoundIsRefusedNamingTheKey) {
  const std::string base = R"({"version": 1, "scene": {"objects": [{"file": "assets/cornell_box.obj"%s}], %s}})";
  const auto job = [&](const std::string& object, const std::string& scene) {
    std::string text = base;
    text.replace(text.find("%s"), 2, object);
    text.replace(text.find("%s"), 2, scene);
    return text;
  };
  const std::pair<std::string, std::string> cases[] = {
      {job("", R"("lights": [{"position": [0, 1, 0], "intensity": 3e38}])"), "scene.lights[0].intensity"},
      {job("", R"("lights": [{"position": [0, 1, 0], "intensity": [1, 2e15, 1]}])"), "scene.lights[0].intensity"},
      {job("", R"("background": [0, 0, 1e16])"), "scene.background"},
      {job("", R"("ambient": [1e20, 0, 0])"), "scene.ambient"},
      {job(R"(, "material": {"emission": [1e30, 1, 1]})", R"("lights": [])"), "scene.objects[0].material.emission"},
  };
  for (const auto& [text, key] : cases) {
    try {
      parse_job(text, kJobPath);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(key), std::string::npos) << what;
      EXPECT_NE(what.find("<= 1000000000000000"), std::string::npos) << what;
    }
  }
  // At the bound is fine.
  EXPECT_NO_THROW(parse_job(job("", R"("lights": [{"position": [0, 1, 0], "intensity": 1e15}])"), kJobPath));
}

}  // namespace
}  // namespace farm
