#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <glm/gtc/matrix_transform.hpp>

#include "renderer/engine.h"
#include "renderer/render_frame.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

RenderSettings path_settings(int width, int height, int spp) {
  RenderSettings s = test::raster_settings(width, height);
  s.engine = EngineKind::Path;
  s.spp = spp;
  s.max_depth = -1;  // unbounded: Russian roulette ends the paths
  return s;
}

double mean_red(const TileBuffer& image) {
  double sum = 0.0;
  const Rect& r = image.rect();
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) sum += image.rgba(x, y).x;
  return sum / (static_cast<double>(r.width()) * r.height());
}

// The model turned inside out: winding and normals reversed, so its front faces inwards.
Model inside_out(Model model) {
  for (Mesh& mesh : model.meshes) {
    for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
    for (glm::vec3& n : mesh.normals) n = -n;
  }
  return model;
}

// A closed sphere of radius 3 that emits `le` and reflects `albedo` diffusely, seen from inside;
// it shines from its front, so its winding faces inwards (or, with `sides` both, either way).
PreparedScene furnace(float albedo, float le, const glm::vec3& eye, const glm::vec3& target,
                      EmissionSides sides = EmissionSides::Front) {
  Material m;
  m.diffuse = glm::vec3(albedo);
  m.specular = glm::vec3(0.0f);
  m.emission = glm::vec3(le);
  m.emission_sides = sides;
  Scene scene;
  Model sphere = test::make_sphere(32, 64);
  if (sides == EmissionSides::Front) sphere = inside_out(std::move(sphere));
  scene.objects.push_back(test::object_of(std::move(sphere), glm::scale(glm::mat4(1.0f), glm::vec3(3.0f)), m));
  scene.camera.position = eye;
  scene.camera.target = target;
  scene.camera.far = 100;
  return PreparedScene(std::move(scene));
}

// Inside a closed sphere that emits Le and reflects a fraction rho diffusely, every point sees
// L = Le + rho * L, so L = Le / (1 - rho) everywhere.
TEST(PathFurnace, ClosedEmissiveLambertianSphereConvergesToLeOverOneMinusAlbedo) {
  // Emitting inwards from its front, and from both faces of an outward winding: the same.
  for (EmissionSides sides : {EmissionSides::Front, EmissionSides::Both}) {
    const PreparedScene prepared = furnace(0.5f, 0.5f, {0.3f, -0.2f, 0.1f}, {1, 0.5f, -1}, sides);
    const TileBuffer image = render_frame(prepared, path_settings(24, 24, 64));
    EXPECT_NEAR(mean_red(image), 1.0, 0.02) << to_string(sides);
    EXPECT_EQ(image.stats().invalid_samples, 0u);
    EXPECT_EQ(image.stats().samples, 24u * 24u * 64u);
  }
}

// A sphere under a uniform white sky of radiance 1, filling the whole view. Whatever a BSDF
// scatters it scatters sky light, so a surface that keeps all the energy is invisible (every
// pixel 1) and one that loses energy shows darker by exactly what it loses.
double mean_of_sphere_under_white_sky(const Material& m, int spp) {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_sphere(48, 96), glm::mat4(1.0f), m));
  scene.background = glm::vec3(1.0f);
  scene.camera.position = {0.0f, 0.4f, 3.0f};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 22;  // the sphere covers even the corners
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  const TileBuffer image = render_frame(prepared, path_settings(24, 24, spp));
  EXPECT_EQ(image.stats().invalid_samples, 0u);
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) EXPECT_EQ(image.rgba(x, y).w, 1.0f) << "the sphere must fill the view";
  return mean_red(image);
}

TEST(PathFurnace, GlossySpheresUnderAWhiteSkyNeitherLoseNorCreateEnergy) {
  // A white Lambertian sphere, a white GGX conductor (alpha 0.1) and a white diffuse base under a
  // rougher coat (alpha 0.25; the layers share the energy, never add). Without the GGX
  // multiple-scattering term the two glossy ones came out 1.4% and 2.9% dark here.
  Material metal;
  metal.diffuse = glm::vec3(0.0f);
  metal.specular = glm::vec3(1.0f);
  metal.shininess = 198;
  Material coated;
  coated.diffuse = glm::vec3(1.0f);
  coated.specular = glm::vec3(0.3f);
  coated.shininess = 30;
  Material white;
  white.diffuse = glm::vec3(1.0f);
  white.specular = glm::vec3(0.0f);
  for (const Material& m : {white, metal, coated}) {
    const double mean = mean_of_sphere_under_white_sky(m, 256);
    std::printf("glossy sphere (ks %.1f, shininess %.0f): mean %.4f\n", m.specular.x, m.shininess, mean);
    EXPECT_NEAR(mean, 1.0, 0.006);
  }
}

TEST(PathFurnace, GlassSphereUnderAWhiteSkyKeepsAllTheEnergy) {
  // Fresnel splits every ray between reflection and refraction and nothing is absorbed: the
  // (eta_i / eta_t)^2 radiance scaling on the way in is undone on the way out.
  Material glass;
  glass.transmission = 1.0f;
  glass.ior = 1.5f;
  const double mean = mean_of_sphere_under_white_sky(glass, 256);
  std::printf("glass sphere: mean %.4f\n", mean);
  EXPECT_NEAR(mean, 1.0, 0.01);
}

// Partly glass, partly a white diffuser (a Phong material with transmission 0.5, and a white
// glTF dielectric 60% transmissive): neither part loses energy, so neither does the surface that
// is one or the other at each hit. (How often each part is picked, which this cannot see,
// MitsubaReference.GlassBallsMatchInMeanByAZTest holds.)
TEST(PathFurnace, PartlyTransmissiveSpheresUnderAWhiteSkyKeepAllTheEnergy) {
  Material half;
  half.diffuse = glm::vec3(1.0f);
  half.transmission = 0.5f;
  half.ior = 1.5f;
  Material gltf;
  set_metal_roughness(gltf, glm::vec3(1.0f), 0.0f, 0.05f);
  gltf.ior = 1.5f;
  gltf.transmission = 0.6f;
  for (const Material& m : {half, gltf}) {
    const double mean = mean_of_sphere_under_white_sky(m, 256);
    std::printf("partly transmissive sphere (t %.1f): mean %.4f\n", m.transmission, mean);
    EXPECT_NEAR(mean, 1.0, 0.01);
  }
}

TEST(PathFurnace, DepthLimitCutsTheSeriesWhereMaxDepthSays) {
  // max_depth 0: only emission seen directly (Le); 1: plus one scattering (Le + rho Le).
  const PreparedScene prepared = furnace(0.5f, 0.5f, {0, 0, 0}, {0, 0, -1});
  RenderSettings settings = path_settings(16, 16, 64);
  settings.max_depth = 0;
  EXPECT_NEAR(mean_red(render_frame(prepared, settings)), 0.5, 1e-4);
  settings.max_depth = 1;
  EXPECT_NEAR(mean_red(render_frame(prepared, settings)), 0.75, 0.01);
}

TEST(PathRussianRoulette, LeavesTheMeanOfADeepFixedDepthRenderUnchanged) {
  const PreparedScene prepared = furnace(0.7f, 0.3f, {0.5f, 0.1f, -0.3f}, {-1, 0.2f, 1});
  RenderSettings fixed = path_settings(16, 16, 64);
  fixed.max_depth = 40;  // 0.7^41 of the series is left out: nothing measurable
  const RenderSettings roulette = path_settings(16, 16, 64);
  const double deep = mean_red(render_frame(prepared, fixed));
  const double ended = mean_red(render_frame(prepared, roulette));
  EXPECT_NEAR(deep, 1.0, 0.01);  // Le / (1 - rho) = 0.3 / 0.3
  EXPECT_NEAR(ended, deep, 0.02);
}

TEST(PathMis, TinyAndLargeLightsGiveTheSameMeanWithNeeMisAsWithBsdfSamplingAlone) {
  Material floor;
  floor.diffuse = glm::vec3(0.8f);
  floor.specular = glm::vec3(0.0f);
  Material tiny, large;
  tiny.emission = glm::vec3(100.0f);
  large.emission = glm::vec3(0.1f);
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_quad({-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}), glm::mat4(1.0f), floor));
  scene.objects.push_back(test::object_of(
      test::make_quad({-0.05f, 1.5f, -0.05f}, {0.05f, 1.5f, -0.05f}, {0.05f, 1.5f, 0.05f}, {-0.05f, 1.5f, 0.05f}),
      glm::mat4(1.0f), tiny));
  scene.objects.push_back(test::object_of(
      test::make_quad({-1.5f, 3, -1.5f}, {1.5f, 3, -1.5f}, {1.5f, 3, 1.5f}, {-1.5f, 3, 1.5f}), glm::mat4(1.0f), large));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 2.5f, 2.5f};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 40;
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  RenderSettings mis = path_settings(8, 8, 1024);
  mis.max_depth = 1;  // direct light only: the two strategies are compared on exactly that
  RenderSettings bsdf_only = mis;
  // BSDF sampling finds the small light (10 cm at 1.5 m) in about one path in a thousand, each
  // find weighing a lot: it needs this many samples to bring its noise near 2%.
  bsdf_only.spp = 32768;
  bsdf_only.light_sampling = LightSampling::BsdfOnly;
  const double a = mean_red(render_frame(prepared, mis));
  const double b = mean_red(render_frame(prepared, bsdf_only));
  std::printf("direct light: NEE+MIS %.4f, BSDF sampling only %.4f\n", a, b);
  EXPECT_GT(a, 0.05);
  EXPECT_NEAR(a, b, 0.08 * b);
}

TEST(PathRenderTile, NanAndInfSamplesAreCountedAndNeverReachThePixel) {
  // A lamp whose radiance is NaN in red and inf in green (a scene built in code: job files refuse
  // such numbers) next to a sane one: every sample that sees the bad lamp is dropped and counted.
  Material bad;
  bad.emission = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), 1.0f};
  Material good;
  good.emission = glm::vec3(1.0f);
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_quad({-2, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-2, 1, 0}), glm::mat4(1.0f), bad));
  scene.objects.push_back(test::object_of(test::make_quad({0, -1, 0}, {2, -1, 0}, {2, 1, 0}, {0, 1, 0}), glm::mat4(1.0f), good));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 0, 3};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 30;
  const PreparedScene prepared(std::move(scene));
  for (int depth : {0, 3}) {  // seen directly; and with next-event estimation sampling lamps
    RenderSettings settings = path_settings(16, 8, 4);
    settings.max_depth = depth;
    const TileBuffer image = render_frame(prepared, settings);
    EXPECT_GT(image.stats().invalid_samples, 8u * 8u * 4u / 2);  // about the left half
    EXPECT_LT(image.stats().invalid_samples, image.stats().samples);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 16; ++x) {
        const glm::vec4 p = image.rgba(x, y);
        ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << x << "," << y;
      }
    }
    EXPECT_NEAR(image.rgba(13, 4).x, 1.0f, 1e-6f);  // the sane lamp, untouched
    EXPECT_EQ(image.rgba(2, 4).x, 0.0f);            // all of its samples were bad: dropped, not NaN
  }
}

TEST(PathRenderTile, AnyTilingAndThreadCountGivesTheSameBits) {
  Material light;
  light.emission = glm::vec3(4.0f);
  Material glossy;
  glossy.diffuse = {0.6f, 0.3f, 0.2f};
  glossy.specular = glm::vec3(0.3f);
  glossy.shininess = 60;
  Material glass;
  glass.transmission = 1;
  glass.ior = 1.5f;
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_box({-3, -1.6f, -3}, {3, -1.2f, 3}), glm::mat4(1.0f), glossy));
  scene.objects.push_back(test::object_of(test::make_sphere(16, 32), glm::mat4(1.0f), glass));
  scene.objects.push_back(test::object_of(test::make_quad({-1, 3, -1}, {1, 3, -1}, {1, 3, 1}, {-1, 3, 1}), glm::mat4(1.0f), light));
  scene.camera.position = {2.5f, 1.5f, 3.5f};
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  RenderSettings settings = path_settings(37, 29, 4);
  settings.seed = 7;
  settings.aovs.depth = settings.aovs.normal = settings.aovs.albedo = settings.aovs.variance = true;
  const TileBuffer whole = test::render_full(prepared, settings);
  int noisy = 0;
  for (int threads : {1, 3}) {
    // Tiles of one pixel never fill a packet of camera rays (4 samples): every ray is traced
    // alone there, and a packet's hits must be the same bits (camera_ray_stream.h).
    for (int tile : {1, 8, 16}) {
      settings.threads = threads;
      settings.tile_size = tile;
      const TileBuffer tiled = render_frame(prepared, settings);
      for (int y = 0; y < 29; ++y) {
        for (int x = 0; x < 37; ++x) {
          ASSERT_EQ(std::memcmp(&whole.rgba(x, y), &tiled.rgba(x, y), sizeof(glm::vec4)), 0) << x << "," << y;
          const float depth_whole = whole.depth(x, y), depth_tiled = tiled.depth(x, y);
          ASSERT_EQ(std::memcmp(&depth_whole, &depth_tiled, sizeof(float)), 0) << x << "," << y;
          ASSERT_EQ(std::memcmp(&whole.normal(x, y), &tiled.normal(x, y), sizeof(glm::vec3)), 0) << x << "," << y;
          ASSERT_EQ(std::memcmp(&whole.albedo(x, y), &tiled.albedo(x, y), sizeof(glm::vec3)), 0) << x << "," << y;
          ASSERT_EQ(std::memcmp(&whole.variance(x, y), &tiled.variance(x, y), sizeof(glm::vec3)), 0) << x << "," << y;
          noisy += whole.variance(x, y).x > 0.0f ? 1 : 0;
        }
      }
    }
  }
  EXPECT_GT(noisy, 4 * 100);  // the variance compared is not all zeros
  // A different seed gives a different (noisy) image.
  settings.seed = 8;
  const TileBuffer other = render_frame(prepared, settings);
  int differ = 0;
  for (int y = 0; y < 29; ++y)
    for (int x = 0; x < 37; ++x) differ += whole.rgba(x, y) != other.rgba(x, y) ? 1 : 0;
  EXPECT_GT(differ, 100);
}

// A lamp seen directly (max_depth 0) on a black background: each sample is either the lamp's Le
// or 0, so a pixel on the lamp's edge whose fraction of hits is p = k / n (its alpha) has the
// sample variance Le^2 * k (n - k) / (n (n - 1)), and its mean estimate that over n.
TEST(PathVarianceAov, EqualsTheSampleVarianceOverSppOfTwoValuedSamples) {
  Material lamp;
  lamp.emission = {3.0f, 1.5f, 0.25f};
  Scene scene;
  // A triangle facing the camera, so its edges cross pixels at every angle.
  scene.objects.push_back(test::object_of(test::make_quad({-1, -1, 0}, {1, -0.7f, 0}, {0.2f, 1, 0}, {-0.9f, 0.6f, 0}),
                                          glm::mat4(1.0f), lamp));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 0, 3};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 50;
  const PreparedScene prepared(std::move(scene));
  const int n = 24;
  RenderSettings settings = path_settings(20, 20, n);
  settings.max_depth = 0;
  settings.aovs.variance = true;
  const TileBuffer image = render_frame(prepared, settings);
  int edge_pixels = 0;
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 20; ++x) {
      const double k = std::round(static_cast<double>(image.rgba(x, y).w) * n);
      for (int c = 0; c < 3; ++c) {
        const double le = lamp.emission[c];
        const double expected = le * le * k * (n - k) / (static_cast<double>(n) * n * (n - 1));
        ASSERT_NEAR(image.variance(x, y)[c], expected, 1e-6 * le * le) << x << "," << y << " channel " << c;
      }
      if (k > 0 && k < n) ++edge_pixels;
    }
  }
  EXPECT_GT(edge_pixels, 10);  // the edges were crossed: not only 0 and full pixels
}

TEST(PathVarianceAov, IsZeroForOneSampleAndZeroForRasterAndWhitted) {
  Material light;
  light.emission = glm::vec3(2.0f);
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_box({-2, -1.2f, -2}, {2, -1, 2})));
  scene.objects.push_back(test::object_of(test::make_quad({-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}), glm::mat4(1.0f), light));
  scene.lights.push_back(Light{Light::Kind::Point, {0, 3, 0}, {}, glm::vec3(10.0f)});
  scene.camera.position = {0, 2, 4};
  scene.camera.target = {0, -1, 0};
  const PreparedScene prepared(std::move(scene));
  for (EngineKind engine : {EngineKind::Path, EngineKind::Raster, EngineKind::Whitted}) {
    for (int spp : {1, 8}) {
      if (engine == EngineKind::Path && spp != 1) continue;
      RenderSettings settings = path_settings(12, 10, spp);
      settings.engine = engine;
      settings.aovs.variance = true;
      const TileBuffer image = render_frame(prepared, settings);
      ASSERT_TRUE(image.aovs().variance);
      double lit = 0.0;
      for (int y = 0; y < 10; ++y) {
        for (int x = 0; x < 12; ++x) {
          ASSERT_EQ(image.variance(x, y), glm::vec3(0.0f)) << to_string(engine) << " spp " << spp;
          lit += image.rgba(x, y).x;
        }
      }
      EXPECT_GT(lit, 0.0) << to_string(engine);
    }
  }
}

// The AOV against the spread of the mean over independent renders: both estimate the variance
// of a pixel's mean, and halving it takes four times the samples.
TEST(PathVarianceAov, MatchesTheSpreadOfTheMeanOverSeedsAndFallsAsOneOverSpp) {
  Material floor;
  floor.diffuse = glm::vec3(0.7f);
  Material light;
  light.emission = glm::vec3(5.0f);
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_quad({-2, 0, 2}, {2, 0, 2}, {2, 0, -2}, {-2, 0, -2}), glm::mat4(1.0f), floor));
  scene.objects.push_back(test::object_of(test::make_quad({-0.5f, 1.5f, -0.5f}, {0.5f, 1.5f, -0.5f}, {0.5f, 1.5f, 0.5f}, {-0.5f, 1.5f, 0.5f}),
                                          glm::mat4(1.0f), light));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 2.5f, 2.5f};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 30;  // the floor fills the view
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  constexpr int kWidth = 16, kHeight = 16, kSeeds = 12;
  const auto red_aov_mean = [&](const TileBuffer& image) {
    double sum = 0.0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) sum += image.variance(x, y).x;
    return sum / (kWidth * kHeight);
  };
  RenderSettings settings = path_settings(kWidth, kHeight, 16);
  settings.max_depth = 3;
  settings.aovs.variance = true;
  // Per pixel over the seeds: the mean of the AOV, and the unbiased variance of the red means.
  std::vector<double> sum(kWidth * kHeight, 0.0), sum2(kWidth * kHeight, 0.0);
  double aov = 0.0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    settings.seed = static_cast<std::uint64_t>(seed);
    const TileBuffer image = render_frame(prepared, settings);
    aov += red_aov_mean(image) / kSeeds;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const double v = image.rgba(x, y).x;
        sum[static_cast<std::size_t>(y * kWidth + x)] += v;
        sum2[static_cast<std::size_t>(y * kWidth + x)] += v * v;
      }
    }
  }
  double spread = 0.0;
  for (std::size_t i = 0; i < sum.size(); ++i) {
    spread += (sum2[i] - sum[i] * sum[i] / kSeeds) / (kSeeds - 1);
  }
  spread /= static_cast<double>(sum.size());
  settings.seed = 0;
  settings.spp = 64;
  const double aov_64 = red_aov_mean(render_frame(prepared, settings));
  std::printf("variance of the mean at 16 spp: AOV %.4g, over %d seeds %.4g; AOV at 64 spp %.4g (ratio %.3f)\n",
              aov, kSeeds, spread, aov_64, aov / aov_64);
  EXPECT_GT(aov, 0.0);
  EXPECT_NEAR(spread / aov, 1.0, 0.2);
  EXPECT_NEAR(aov / aov_64, 4.0, 0.6);
}

// A lamp 1 above a floor, seen from the side and from below: `lamp` is the lamp's model (in its own space) and
// `lamp_to_world` places it.
PreparedScene lamp_over_floor(Model lamp, const glm::mat4& lamp_to_world, EmissionSides sides) {
  Material floor;
  floor.diffuse = glm::vec3(0.8f);
  floor.specular = glm::vec3(0.0f);
  Material light;
  light.emission = glm::vec3(3.0f);
  light.emission_sides = sides;
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_quad({-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, {-3, 0, -3}), glm::mat4(1.0f), floor));
  scene.objects.push_back(test::object_of(std::move(lamp), lamp_to_world, light));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 0.7f, 3.5f};  // below the lamp: it sees the lamp's underside
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 40;
  scene.camera.far = 50;
  return PreparedScene(std::move(scene));
}

// Facing down (counter-clockwise seen from below) and facing up, at height 1.
Model lamp_facing_down() { return test::make_quad({-0.5f, 1, -0.5f}, {0.5f, 1, -0.5f}, {0.5f, 1, 0.5f}, {-0.5f, 1, 0.5f}); }
Model lamp_facing_up() { return test::make_quad({-0.5f, 1, 0.5f}, {0.5f, 1, 0.5f}, {0.5f, 1, -0.5f}, {-0.5f, 1, -0.5f}); }

// The floor's direct light, by next-event estimation with MIS and by BSDF sampling alone.
std::pair<double, double> direct_light_both_ways(const PreparedScene& scene) {
  RenderSettings settings = path_settings(16, 16, 256);
  settings.max_depth = 1;
  RenderSettings bsdf_only = settings;
  bsdf_only.spp = 2048;
  bsdf_only.light_sampling = LightSampling::BsdfOnly;
  return {mean_red(render_frame(scene, settings)), mean_red(render_frame(scene, bsdf_only))};
}

TEST(PathEmitterSides, ALampLightsFromItsFrontFaceOnlyUnlessItsMaterialSaysBoth) {
  const auto [down_nee, down_bsdf] =
      direct_light_both_ways(lamp_over_floor(lamp_facing_down(), glm::mat4(1.0f), EmissionSides::Front));
  const auto [up_nee, up_bsdf] =
      direct_light_both_ways(lamp_over_floor(lamp_facing_up(), glm::mat4(1.0f), EmissionSides::Front));
  const auto [both_nee, both_bsdf] =
      direct_light_both_ways(lamp_over_floor(lamp_facing_up(), glm::mat4(1.0f), EmissionSides::Both));
  std::printf("floor under a lamp facing down: NEE+MIS %.4f, BSDF %.4f; facing up %.4f %.4f; "
              "facing up, both sides %.4f %.4f\n",
              down_nee, down_bsdf, up_nee, up_bsdf, both_nee, both_bsdf);
  EXPECT_GT(down_nee, 0.05);
  // The two strategies agree: the light sampler's back-facing picks add nothing, and the MIS
  // weights of the hits BSDF sampling makes stay consistent with them.
  EXPECT_NEAR(down_nee, down_bsdf, 0.03 * down_nee);
  // The lamp's back lights nothing, and it is all the camera sees of the lamp.
  EXPECT_EQ(up_nee, 0.0);
  EXPECT_EQ(up_bsdf, 0.0);
  // Both faces shining: the floor gets what the front-only lamp facing it gives.
  EXPECT_NEAR(both_nee, down_nee, 0.03 * down_nee);
  EXPECT_NEAR(both_bsdf, down_nee, 0.03 * down_nee);
}

TEST(PathEmitterSides, ALampSeenDirectlyIsDarkFromBehind) {
  for (const bool flipped : {false, true}) {
    Material light;
    light.emission = {2.0f, 1.0f, 0.5f};
    Scene scene;
    scene.objects.push_back(test::object_of(flipped ? lamp_facing_up() : lamp_facing_down(), glm::mat4(1.0f), light));
    scene.background = glm::vec3(0.0f);
    scene.camera.position = {0, -1, 0.01f};  // below it, looking up
    scene.camera.target = {0, 1, 0};
    const PreparedScene prepared(std::move(scene));
    RenderSettings settings = path_settings(8, 8, 4);
    settings.max_depth = 0;
    const TileBuffer image = render_frame(prepared, settings);
    EXPECT_EQ(image.rgba(4, 4), flipped ? glm::vec4(0, 0, 0, 1) : glm::vec4(2, 1, 0.5f, 1)) << flipped;
  }
}

// A transform that mirrors the model keeps the front on the same side of the surface (the
// inverse-transpose normal), for the light sampler as for the hits: a model lamp facing up at
// y = 0, mirrored upside down to y = 1, faces the floor and lights it as the unmirrored lamp
// facing down does, by either strategy.
TEST(PathEmitterSides, AMirroringTransformKeepsTheLampsFrontWhereItsWindingSays) {
  const glm::mat4 mirror = glm::translate(glm::mat4(1.0f), glm::vec3(0, 1, 0)) *
                           glm::scale(glm::mat4(1.0f), glm::vec3(1, -1, 1));
  const Model model_facing_up = test::make_quad({-0.5f, 0, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 0, -0.5f}, {-0.5f, 0, -0.5f});
  const auto [nee, bsdf] = direct_light_both_ways(lamp_over_floor(model_facing_up, mirror, EmissionSides::Front));
  const auto [reference, unused] =
      direct_light_both_ways(lamp_over_floor(lamp_facing_down(), glm::mat4(1.0f), EmissionSides::Front));
  std::printf("mirrored lamp: NEE+MIS %.4f, BSDF %.4f, the lamp facing down %.4f\n", nee, bsdf, reference);
  EXPECT_NEAR(nee, reference, 0.01 * reference);
  EXPECT_NEAR(bsdf, reference, 0.03 * reference);
}

// A directional light casts shadows: a box floating over a ground, the light slanting down at
// 45 degrees, seen from straight above. Direct light only (max_depth 1, a black background), so
// every lit ground pixel is kd / pi * cos 45 exactly and every shadowed one 0. (Its shadow rays
// once ran to a point 1e30 away, which made every hit too near to count: no shadow at all.)
TEST(PathDirectionalLight, CastsAShadowBesideTheBoxThatBlocksIt) {
  Scene scene;
  Material ground;
  ground.diffuse = glm::vec3(0.5f);
  scene.objects.push_back(test::object_of(test::make_quad({-3, 0, 3}, {3, 0, 3}, {3, 0, -3}, {-3, 0, -3}), glm::mat4(1.0f), ground));
  scene.objects.push_back(test::object_of(test::make_box({-0.3f, 0.5f, -0.3f}, {0.3f, 1.1f, 0.3f})));
  Light sun;
  sun.kind = Light::Kind::Directional;
  sun.direction = glm::normalize(glm::vec3(1.0f, -1.0f, 0.0f));  // travelling towards +x
  sun.intensity = glm::vec3(1.0f);
  scene.lights = {sun};
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0.0f, 5.0f, 0.0f};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  scene.camera.up = {0.0f, 0.0f, -1.0f};  // image right is +x, image down is +z
  scene.camera.far = 20.0f;
  const PreparedScene prepared(std::move(scene));
  RenderSettings s = path_settings(64, 64, 4);
  s.max_depth = 1;
  const TileBuffer image = render_frame(prepared, s);
  // World x at pixel column px, on the ground (the view is 2 tan(22.5 deg) * 5 wide there).
  const auto ground_x = [](int px) { return (2.0f * (static_cast<float>(px) + 0.5f) / 64.0f - 1.0f) * 5.0f * std::tan(glm::radians(22.5f)); };
  const float lit = 0.5f / glm::pi<float>() * std::cos(glm::radians(45.0f));
  int shadowed = 0, checked = 0;
  for (int px = 0; px < 64; ++px) {
    const float x = ground_x(px);
    const float red = image.rgba(px, 32).x;  // the row through z = 0
    if (x > 0.45f && x < 1.3f) {  // the box's shadow: from its bottom's 0.5 to its top's 1.1 beyond it
      EXPECT_LT(red, 1e-6f) << "x " << x;
      ++shadowed;
    } else if (x < -0.35f || x > 1.45f) {
      EXPECT_NEAR(red, lit, 1e-4f) << "x " << x;
      ++checked;
    }
  }
  EXPECT_GT(shadowed, 8);
  EXPECT_GT(checked, 20);
}

}  // namespace
}  // namespace farm
