#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "renderer/engine.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/trace/fresnel.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

using test::make_box;
using test::make_quad;
using test::object_of;

RenderSettings whitted_settings(int width, int height, AovSet aovs = {}) {
  RenderSettings s = test::raster_settings(width, height, aovs);
  s.engine = EngineKind::Whitted;
  return s;
}

// The pixel whose centre ray passes closest to world point p.
glm::ivec2 pixel_of(const Camera& camera, const glm::vec3& p, int width, int height) {
  const glm::mat4 vp = camera.projection_matrix(camera.aspect_for(width, height)) * camera.view_matrix();
  const glm::vec4 clip = vp * glm::vec4(p, 1.0f);
  const float x = (clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(width);
  const float y = (0.5f - clip.y / clip.w * 0.5f) * static_cast<float>(height);
  return {static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y))};
}

TEST(Fresnel, MatchesKnownValues) {
  for (float n : {1.33f, 1.5f, 2.4f}) {
    const float normal = (n - 1.0f) / (n + 1.0f);
    EXPECT_NEAR(fresnel_dielectric(1.0f, 1.0f, n), normal * normal, 1e-6f) << n;
    EXPECT_NEAR(fresnel_dielectric(1.0f, n, 1.0f), normal * normal, 1e-6f) << n;  // symmetric
    EXPECT_NEAR(fresnel_dielectric(1e-4f, 1.0f, n), 1.0f, 1e-3f) << n;              // grazing
  }
  // Glass to air beyond the critical angle (41.8 degrees for n = 1.5): total internal reflection.
  EXPECT_EQ(fresnel_dielectric(std::cos(glm::radians(45.0f)), 1.5f, 1.0f), 1.0f);
  EXPECT_LT(fresnel_dielectric(std::cos(glm::radians(40.0f)), 1.5f, 1.0f), 1.0f);
  // Air to glass at 45 degrees: Rs = 0.0920, Rp = 0.00847, mean 0.0503 (textbook values).
  EXPECT_NEAR(fresnel_dielectric(std::cos(glm::radians(45.0f)), 1.0f, 1.5f), 0.0503f, 2e-4f);
}

TEST(WhittedShadow, BlocksLightBehindOccluder) {
  Material floor;
  floor.ambient = glm::vec3(1.0f);
  floor.diffuse = glm::vec3(0.8f);
  Scene scene;
  scene.objects.push_back(object_of(make_quad({-4, 0, 4}, {4, 0, 4}, {4, 0, -4}, {-4, 0, -4}), glm::mat4(1.0f), floor));
  // A small box hovering between the light and the floor point (1, 0, 0).
  scene.objects.push_back(object_of(make_box({0.8f, 1.9f, -0.2f}, {1.2f, 2.1f, 0.2f})));
  scene.lights.push_back(Light{Light::Kind::Point, {1, 4, 0}, {}, glm::vec3(10.0f)});
  scene.ambient = glm::vec3(0.1f);
  scene.camera.position = {-3, 3, 3};
  scene.camera.target = {0.5f, 0, 0};
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  const RenderSettings settings = whitted_settings(120, 90);
  const TileBuffer image = test::render_full(prepared, settings);

  const glm::ivec2 shadowed = pixel_of(prepared.scene().camera, {1, 0, 0}, 120, 90);
  const glm::vec4 c = image.rgba(shadowed.x, shadowed.y);
  EXPECT_NEAR(c.x, 0.1f, 1e-5f);  // ka * ambient only
  EXPECT_NEAR(c.y, 0.1f, 1e-5f);
  const glm::ivec2 lit = pixel_of(prepared.scene().camera, {-1, 0, 1}, 120, 90);
  EXPECT_GT(image.rgba(lit.x, lit.y).x, 0.3f);

  // With shadows off the same pixel gets the light.
  RenderSettings no_shadows = settings;
  no_shadows.shadows = false;
  EXPECT_GT(test::render_full(prepared, no_shadows).rgba(shadowed.x, shadowed.y).x, 0.3f);
}

TEST(WhittedMirror, ReflectsAColouredObjectAtTheExpectedPixel) {
  Material mirror;
  mirror.ambient = glm::vec3(0.0f);
  mirror.diffuse = glm::vec3(0.0f);
  mirror.shininess = 1000;
  mirror.ior = 50;  // a metal-like, strongly reflecting dielectric: F ~ 0.92 at normal incidence
  Material red;
  red.ambient = {1, 0, 0};
  red.diffuse = {1, 0, 0};
  Scene scene;
  scene.objects.push_back(object_of(make_quad({-6, 0, 6}, {6, 0, 6}, {6, 0, -6}, {-6, 0, -6}), glm::mat4(1.0f), mirror));
  // Camera C; the floor point P mirrors it towards Q = P + (P - C') with C' = C mirrored in y.
  const glm::vec3 C{0, 2, 4}, P{0, 0, 1}, C_mirror{C.x, -C.y, C.z};
  const glm::vec3 Q = P + 1.5f * (P - C_mirror);
  scene.objects.push_back(object_of(make_box(Q - glm::vec3(0.3f), Q + glm::vec3(0.3f)), glm::mat4(1.0f), red));
  scene.lights.push_back(Light{Light::Kind::Point, {0, 5, 2}, {}, glm::vec3(20.0f)});
  scene.ambient = glm::vec3(0.2f);
  scene.camera.position = C;
  scene.camera.target = {0, 0, 0};
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  const RenderSettings settings = whitted_settings(100, 100);
  const TileBuffer image = test::render_full(prepared, settings);
  const glm::ivec2 at = pixel_of(prepared.scene().camera, P, 100, 100);
  const glm::vec4 c = image.rgba(at.x, at.y);
  EXPECT_GT(c.x, 0.1f);
  EXPECT_GT(c.x, 5.0f * c.y) << "the mirror should show the red box";
  // Without recursion the mirror shows only its own (black) shading.
  RenderSettings flat = settings;
  flat.max_depth = 0;
  EXPECT_LT(test::render_full(prepared, flat).rgba(at.x, at.y).x, 0.01f);
}

TEST(WhittedGlass, ClearGlassBlockPassesTheBackgroundWithoutLosingEnergy) {
  Material glass;
  glass.ambient = glm::vec3(0.0f);
  glass.diffuse = glm::vec3(0.0f);
  glass.transmission = 1.0f;
  glass.ior = 1.5f;
  Scene scene;
  scene.objects.push_back(object_of(make_box({-1, -1, -0.5f}, {1, 1, 0.5f}), glm::mat4(1.0f), glass));
  scene.background = {0.2f, 0.4f, 0.6f};
  scene.camera.position = {0, 0, 5};
  scene.camera.target = {0, 0, 0};
  const PreparedScene prepared(std::move(scene));
  const TileBuffer image = test::render_full(prepared, whitted_settings(41, 41));
  // At normal incidence each face reflects F = 0.04 and transmits the rest; every path ends in
  // the background, so reflection plus transmission add back up to it (up to the light still
  // bouncing inside after max_depth, about F^2 of it).
  const glm::vec4 c = image.rgba(20, 20);
  EXPECT_NEAR(c.x, 0.2f, 0.005f);
  EXPECT_NEAR(c.y, 0.4f, 0.005f);
  EXPECT_NEAR(c.z, 0.6f, 0.005f);
  // With refraction only one level deep (max_depth 1) the light reflected inside is lost.
  RenderSettings shallow = whitted_settings(41, 41);
  shallow.max_depth = 1;
  EXPECT_LT(test::render_full(prepared, shallow).rgba(20, 20).z, 0.58f);
}

TEST(WhittedRenderTile, AnyTilingAndThreadCountGivesTheSameBits) {
  Material mirror;
  mirror.shininess = 1000;
  mirror.ior = 3;
  Scene scene;
  scene.objects.push_back(object_of(test::make_sphere(24, 48), glm::scale(glm::mat4(1.0f), {1.0f, 1.4f, 0.8f}), mirror));
  scene.objects.push_back(object_of(make_box({-3, -1.6f, -3}, {3, -1.2f, 3})));
  scene.camera.position = {2.5f, 1.5f, 3.5f};
  scene.camera.far = 50;
  scene.lights.push_back(Light{Light::Kind::Point, {3, 4, 2}, {}, glm::vec3(20.0f)});
  const PreparedScene prepared(std::move(scene));
  AovSet aovs;
  aovs.depth = aovs.bvh_cost = aovs.variance = true;
  RenderSettings settings = whitted_settings(67, 43, aovs);
  settings.spp = 2;
  const TileBuffer whole = test::render_full(prepared, settings);
  for (int threads : {1, 3}) {
    for (int tile : {8, 32}) {
      settings.threads = threads;
      settings.tile_size = tile;
      const TileBuffer tiled = render_frame(prepared, settings);
      for (int y = 0; y < 43; ++y)
        for (int x = 0; x < 67; ++x) {
          ASSERT_EQ(whole.rgba(x, y), tiled.rgba(x, y)) << x << "," << y;
          ASSERT_EQ(whole.bvh_cost(x, y), tiled.bvh_cost(x, y));
          ASSERT_EQ(tiled.variance(x, y), glm::vec3(0.0f));  // no Monte Carlo noise to report
        }
    }
  }
}

// A tile's camera rays go a packet of 8 at a time, across pixels, and the shadow rays of a
// packet's hits a packet per light: the image must be, bit for bit, the one traced ray by ray.
// Tiles of one pixel at 4 samples never fill a packet (every ray is traced alone); tiles of
// 16 and the whole frame do. Three lights (one directional, one below the floor that every
// point faces away from), shadows that fall, a mirror and glass (whose own rays go alone).
TEST(WhittedRenderTile, PacketsGiveTheImageOfRaysTracedOneByOne) {
  Material mirror;
  mirror.shininess = 1000;
  mirror.ior = 3;
  Material glass;
  glass.diffuse = glm::vec3(0.0f);
  glass.ior = 1.5f;
  glass.transmission = 1.0f;
  Scene scene;
  scene.objects.push_back(object_of(test::make_sphere(16, 32), glm::scale(glm::mat4(1.0f), {1.0f, 1.4f, 0.8f}), mirror));
  scene.objects.push_back(object_of(test::make_sphere(12, 24), test::placed({1.6f, -0.4f, 1.0f}, {0, 1, 0}, 0.0f, glm::vec3(0.6f)), glass));
  scene.objects.push_back(object_of(make_box({-1.9f, -1.2f, 0.6f}, {-1.1f, 0.2f, 1.4f})));
  scene.objects.push_back(object_of(make_box({-3, -1.6f, -3}, {3, -1.2f, 3})));
  scene.camera.position = {2.5f, 1.5f, 3.5f};
  scene.camera.far = 50;
  scene.lights.push_back(Light{Light::Kind::Point, {3, 4, 2}, {}, glm::vec3(20.0f)});
  scene.lights.push_back(Light{Light::Kind::Directional, {}, {0.4f, -1.0f, -0.3f}, glm::vec3(0.5f)});
  scene.lights.push_back(Light{Light::Kind::Point, {0, -5, 0}, {}, glm::vec3(30.0f)});
  const PreparedScene prepared(std::move(scene));
  RenderSettings settings = whitted_settings(53, 41);
  settings.spp = 4;
  settings.tile_size = 1;
  const TileBuffer alone = render_frame(prepared, settings);
  RenderSettings no_shadows = settings;
  no_shadows.shadows = false;
  const TileBuffer unshadowed = render_frame(prepared, no_shadows);
  int shadowed = 0;
  for (int y = 0; y < 41; ++y)
    for (int x = 0; x < 53; ++x) shadowed += alone.rgba(x, y) != unshadowed.rgba(x, y);
  EXPECT_GT(shadowed, 53 * 41 / 10);  // the shadows show
  for (int tile : {16, 64}) {
    settings.tile_size = tile;
    const TileBuffer packets = render_frame(prepared, settings);
    for (int y = 0; y < 41; ++y)
      for (int x = 0; x < 53; ++x) ASSERT_EQ(alone.rgba(x, y), packets.rgba(x, y)) << x << "," << y << ", tiles of " << tile;
  }
}

// Four emissive quads side by side in front of the camera, with no lights and no ambient, so a
// pixel shows ke or nothing: facing the camera; facing away; facing away but shining from both
// sides; and a quad wound facing away whose object is mirrored through its own plane, which turns
// its front (where the model's winding says) towards the camera.
TEST(CrossEngine, RasterAndWhittedShowEmissionOnlyFromTheEmittingSide) {
  Material front, both;
  front.emission = {2.0f, 1.0f, 0.5f};
  both = front;
  both.emission_sides = EmissionSides::Both;
  const auto facing_camera = [](float x) {
    return make_quad({x - 0.7f, -0.7f, 0}, {x + 0.7f, -0.7f, 0}, {x + 0.7f, 0.7f, 0}, {x - 0.7f, 0.7f, 0});
  };
  const auto facing_away = [](float x) {
    return make_quad({x - 0.7f, 0.7f, 0}, {x + 0.7f, 0.7f, 0}, {x + 0.7f, -0.7f, 0}, {x - 0.7f, -0.7f, 0});
  };
  Scene scene;
  scene.objects.push_back(object_of(facing_camera(-3), glm::mat4(1.0f), front));
  scene.objects.push_back(object_of(facing_away(-1), glm::mat4(1.0f), front));
  scene.objects.push_back(object_of(facing_away(1), glm::mat4(1.0f), both));
  scene.objects.push_back(object_of(facing_away(3), glm::scale(glm::mat4(1.0f), {1, 1, -1}), front));
  scene.ambient = glm::vec3(0.0f);
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 0, 8};
  scene.camera.target = {0, 0, 0};
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  const glm::vec3 lit = front.emission, dark(0.0f);
  const glm::vec3 expected[] = {lit, dark, lit, lit};
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    for (int spp : {1, 4}) {  // pixel centres only, and supersampled (another raster set-up)
      RenderSettings settings = whitted_settings(96, 32);
      settings.engine = engine;
      settings.spp = spp;
      const TileBuffer image = render_frame(prepared, settings);
      for (int i = 0; i < 4; ++i) {
        const glm::ivec2 p = pixel_of(prepared.scene().camera, {-3.0f + 2.0f * static_cast<float>(i), 0, 0}, 96, 32);
        EXPECT_EQ(image.rgba(p.x, p.y), glm::vec4(expected[i], 1.0f))
            << to_string(engine) << " spp " << spp << ", quad " << i;
      }
    }
  }
}

TEST(CrossEngine, WhittedWithoutShadowsOrBouncesMatchesRasterOnTheCow) {
  const std::filesystem::path shared = FARM_SHARED_ASSETS;
  if (!std::filesystem::exists(shared / "dae/cow.dae")) GTEST_SKIP() << "needs ../shared";
  JobLoadOptions load;
  load.asset_root = std::filesystem::canonical(shared);
  const Job job = load_job(std::filesystem::path(FARM_SOURCE_DIR) / "jobs/cow.json", load);
  const PreparedScene prepared(build_scene(job));
  RenderSettings raster = job.render;
  raster.engine = EngineKind::Raster;
  RenderSettings whitted = job.render;
  whitted.engine = EngineKind::Whitted;
  whitted.shadows = false;
  whitted.max_depth = 0;
  const TileBuffer a = render_frame(prepared, raster), b = render_frame(prepared, whitted);
  int agree = 0;
  const int pixels = job.render.width * job.render.height;
  for (int y = 0; y < job.render.height; ++y)
    for (int x = 0; x < job.render.width; ++x) {
      const glm::vec4 d = glm::abs(a.rgba(x, y) - b.rgba(x, y));
      agree += (std::max({d.x, d.y, d.z}) <= 2.0f / 255.0f) ? 1 : 0;
    }
  std::printf("raster vs whitted: %d of %d pixels within 2/255 (%.3f%%)\n", agree, pixels, 100.0 * agree / pixels);
  EXPECT_GE(agree, pixels * 99 / 100);
}

}  // namespace
}  // namespace farm
