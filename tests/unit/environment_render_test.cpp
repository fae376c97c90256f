// The environment light through every engine, against answers known in closed form: a convex
// Lambertian object under a constant environment L reflects kd * L; under a sky that is white
// above the horizon and black below, a point facing n reflects kd * (1 + n.y) / 2. The
// rasterizer and the Whitted tracer take that as their ambient term, the path tracer reaches it
// by sampling (the map by luminance, the BSDF, both weighted by MIS, or the BSDF alone).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "renderer/engine.h"
#include "renderer/render_frame.h"
#include "renderer/texture/environment_light.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

constexpr int kSize = 32;

Material lambertian(const glm::vec3& kd) {
  Material m;
  m.ambient = glm::vec3(1.0f);
  m.diffuse = kd;
  m.specular = glm::vec3(0.0f);
  return m;
}

// White above the horizon, black below, 256 x 128.
std::shared_ptr<const Texture> horizon_map() {
  std::vector<glm::vec4> texels;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 256; ++x) texels.push_back(y < 64 ? glm::vec4(1.0f) : glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  return std::make_shared<const Texture>(256, 128, std::move(texels));
}

// One object seen from the front; with `fill`, close enough that it covers the whole view.
Scene scene_of(Model model, const Material& m, std::shared_ptr<const EnvironmentLight> environment, bool fill) {
  Scene scene;
  scene.objects.push_back(test::object_of(std::move(model), glm::mat4(1.0f), m));
  scene.environment = std::move(environment);
  scene.camera.position = {0.0f, 0.4f, 3.0f};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  scene.camera.fov_y_degrees = fill ? 22.0f : 50.0f;
  scene.camera.far = 50.0f;
  return scene;
}

RenderSettings settings_for(EngineKind engine, int spp, AovSet aovs = {}) {
  RenderSettings s = test::raster_settings(kSize, kSize, aovs);
  s.engine = engine;
  s.spp = spp;
  s.max_depth = engine == EngineKind::Path ? -1 : 5;
  return s;
}

TEST(EnvironmentRender, RasterAndWhittedShowAConstantEnvironmentAndReflectKdTimesIt) {
  const glm::vec3 kd(0.6f, 0.3f, 0.2f), radiance(0.5f, 0.7f, 0.9f);
  const auto environment = std::make_shared<const EnvironmentLight>(radiance, 2.0f, 0.0f, nullptr);
  const PreparedScene prepared(
      scene_of(test::make_box(glm::vec3(-0.5f), glm::vec3(0.5f)), lambertian(kd), environment, false));
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    const TileBuffer image = test::render_full(prepared, settings_for(engine, 1));
    int object = 0, sky = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const glm::vec4 p = image.rgba(x, y);
        const glm::vec3 want = p.w > 0.0f ? kd * radiance * 2.0f : radiance * 2.0f;
        (p.w > 0.0f ? object : sky) += 1;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(p[c], want[c], 1e-5f) << to_string(engine) << " at " << x << "," << y;
      }
    EXPECT_GT(object, 100) << to_string(engine);
    EXPECT_GT(sky, 100) << to_string(engine);
  }
}

TEST(EnvironmentRender, RasterAndWhittedReflectKsTimesAConstantEnvironmentFromAGlossyMetal) {
  // kd 0, ks 0.8, not a mirror: without the glossy part of the ambient term it was black.
  Material metal = lambertian(glm::vec3(0.0f));
  metal.specular = glm::vec3(0.8f, 0.6f, 0.3f);
  metal.shininess = 50.0f;
  const glm::vec3 radiance(0.5f, 0.7f, 0.9f);
  const PreparedScene prepared(scene_of(test::make_box(glm::vec3(-0.5f), glm::vec3(0.5f)), metal,
                                        std::make_shared<const EnvironmentLight>(radiance, 1.0f, 0.0f, nullptr), false));
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    const TileBuffer image = test::render_full(prepared, settings_for(engine, 1));
    int object = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const glm::vec4 p = image.rgba(x, y);
        if (p.w == 0.0f) continue;
        ++object;
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(p[c], metal.specular[c] * radiance[c], 1e-5f) << to_string(engine);
      }
    EXPECT_GT(object, 100) << to_string(engine);
  }
}

TEST(EnvironmentRender, TheAmbientTermOfRasterAndWhittedFollowsTheSkysIrradiance) {
  const auto environment = std::make_shared<const EnvironmentLight>(glm::vec3(1.0f), 1.0f, 0.0f, horizon_map());
  const PreparedScene prepared(scene_of(test::make_sphere(48, 96), lambertian(glm::vec3(1.0f)), environment, true));
  AovSet aovs;
  aovs.normal = true;
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    const TileBuffer image = test::render_full(prepared, settings_for(engine, 1, aovs));
    double worst = 0.0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        ASSERT_EQ(image.rgba(x, y).w, 1.0f) << "the sphere must fill the view";
        const float want = (1.0f + image.normal(x, y).y) / 2.0f;
        worst = std::max(worst, static_cast<double>(std::fabs(image.rgba(x, y).x - want)));
      }
    EXPECT_LT(worst, 0.01) << to_string(engine);
  }
}

// The mean over the image of (pixel - kd * expected(first normal)) and its standard error, from
// the variance AOV.
struct Deviation {
  double mean = 0.0, error = 0.0, expected = 0.0;
};
template <typename Expected>
Deviation deviation_of(const TileBuffer& image, float kd, Expected&& expected) {
  Deviation d;
  double variance = 0.0;
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      EXPECT_EQ(image.rgba(x, y).w, 1.0f) << "the sphere must fill the view";
      const double want = kd * expected(image.normal(x, y));
      d.mean += image.rgba(x, y).x - want;
      d.expected += want;
      variance += image.variance(x, y).x;
    }
  const double n = kSize * kSize;
  d.mean /= n;
  d.expected /= n;
  d.error = std::sqrt(variance) / n;
  return d;
}

TEST(EnvironmentRender, ThePathTracerReflectsAlbedoTimesTheEnvironmentWithAndWithoutLightSampling) {
  AovSet aovs;
  aovs.normal = true;
  aovs.variance = true;
  const float kd = 0.7f;
  struct Case {
    const char* name;
    std::shared_ptr<const EnvironmentLight> light;
    float (*expected)(const glm::vec3& n);
  };
  const Case cases[] = {
      {"constant", std::make_shared<const EnvironmentLight>(glm::vec3(1.0f), 1.0f, 0.0f, nullptr),
       [](const glm::vec3&) { return 1.0f; }},
      {"horizon", std::make_shared<const EnvironmentLight>(glm::vec3(1.0f), 1.0f, 70.0f, horizon_map()),
       [](const glm::vec3& n) { return (1.0f + n.y) / 2.0f; }},
  };
  for (const Case& c : cases) {
    const PreparedScene prepared(scene_of(test::make_sphere(48, 96), lambertian(glm::vec3(kd)), c.light, true));
    for (LightSampling sampling : {LightSampling::NeeMis, LightSampling::BsdfOnly}) {
      RenderSettings s = settings_for(EngineKind::Path, 128, aovs);
      s.light_sampling = sampling;
      const TileBuffer image = render_frame(prepared, s);
      EXPECT_EQ(image.stats().invalid_samples, 0u);
      const Deviation d = deviation_of(image, kd, c.expected);
      std::printf("%s, %s: mean %.5f, expected %.5f (%+.2f standard errors)\n", c.name,
                  sampling == LightSampling::NeeMis ? "nee-mis" : "bsdf", d.mean + d.expected, d.expected,
                  d.mean / d.error);
      // Four standard errors, and 0.5% for the pixel's footprint (the normal is sample 0's).
      EXPECT_LT(std::fabs(d.mean), 4.0 * d.error + 0.005 * d.expected) << c.name;
    }
  }
}

TEST(EnvironmentRender, EveryEngineGivesTheSameBitsWhateverTheTilesAndThreads) {
  const auto environment = std::make_shared<const EnvironmentLight>(glm::vec3(0.8f, 0.9f, 1.0f), 1.3f, 20.0f, horizon_map());
  const PreparedScene prepared(
      scene_of(test::make_box(glm::vec3(-0.5f), glm::vec3(0.5f)), lambertian(glm::vec3(0.5f)), environment, false));
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    RenderSettings whole = settings_for(engine, 4);
    whole.tile_size = kSize;
    whole.threads = 1;
    RenderSettings tiled = whole;
    tiled.tile_size = 7;
    tiled.threads = 3;
    const TileBuffer a = render_frame(prepared, whole), b = render_frame(prepared, tiled);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        ASSERT_EQ(std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)), 0)
            << to_string(engine) << " at " << x << "," << y;
      }
  }
}

}  // namespace
}  // namespace farm
