// glTF's alpha in every engine (docs/architecture.md, §8.4), checked without a second renderer:
// a masked quad shows what lies behind it exactly where its alpha, resampled here along the same
// camera rays, is below the cutoff; a blended one stops a share of the rays equal to its
// coverage; and an occluder cut out everywhere changes no pixel at all, shadows included.
#include <gtest/gtest.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "renderer/accel/cutout_intersector.h"
#include "renderer/engine.h"
#include "renderer/render_frame.h"
#include "renderer/texture/material_textures.h"
#include "renderer/trace/sampler.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

constexpr int kSide = 8;  // texels on a side: alpha 1 and 0 in a checker
constexpr int kWidth = 48, kHeight = 40;
const glm::vec3 kGlow{1.0f, 0.5f, 0.0f};
const glm::vec3 kBackground{0.0f, 0.0f, 0.25f};

float texel_alpha(int i, int j) { return (i + j) % 2 == 0 ? 1.0f : 0.0f; }

// Bilinear alpha with repeat wrapping, texel centres at (i + 0.5) / side: Texture::sample's rule
// for level 0, written again.
float bilinear_alpha(glm::vec2 uv) {
  const float x = uv.x * kSide - 0.5f, y = uv.y * kSide - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const auto at = [](int i, int j) { return texel_alpha(((i % kSide) + kSide) % kSide, ((j % kSide) + kSide) % kSide); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// The square [-1, 1]^2 on z = 0, u along +x, v falling along +y, glowing kGlow from both sides.
const glm::vec3 kCorner[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};

Material glowing(AlphaMode mode, float alpha, bool checker) {
  Material m;
  m.diffuse = glm::vec3(0.0f);
  m.ambient = glm::vec3(0.0f);
  m.emission = kGlow;
  m.emission_sides = EmissionSides::Both;
  m.alpha_mode = mode;
  m.alpha = alpha;
  if (checker) {
    std::vector<glm::vec4> texels;
    for (int j = 0; j < kSide; ++j)
      for (int i = 0; i < kSide; ++i) texels.emplace_back(1.0f, 1.0f, 1.0f, texel_alpha(i, j));
    auto textures = std::make_shared<MaterialTextures>();
    textures->base_colour.texture = std::make_shared<const Texture>(kSide, kSide, std::move(texels));
    textures->base_colour.sampler.mipmaps = false;
    m.textures = textures;
  }
  return m;
}

Scene quad_scene(const Material& m) {
  Model model = test::make_quad(kCorner[0], kCorner[1], kCorner[2], kCorner[3]);
  model.meshes[0].uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  Scene scene;
  scene.objects.push_back(test::object_of(model, glm::mat4(1.0f), m));
  scene.ambient = glm::vec3(0.0f);
  scene.background = kBackground;
  scene.camera.position = {0.3f, 0.2f, 3.0f};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  return scene;
}

RenderSettings settings_for(EngineKind engine, int spp = 1) {
  RenderSettings s = test::raster_settings(kWidth, kHeight);
  s.engine = engine;
  s.spp = spp;
  s.max_depth = 0;
  return s;
}

// Where a camera ray meets the plane z = 0, as uv; false outside the square's inner part.
bool ray_uv(const Ray& ray, glm::vec2& uv) {
  const double t = -static_cast<double>(ray.origin.z) / ray.direction.z;
  const double x = ray.origin.x + t * ray.direction.x, y = ray.origin.y + t * ray.direction.y;
  if (!(t > 0.0) || std::fabs(x) > 0.98 || std::fabs(y) > 0.98) return false;
  uv = glm::vec2(static_cast<float>((x + 1) / 2), static_cast<float>((1 - y) / 2));
  return true;
}

TEST(AlphaCutout, AMaskedQuadShowsTheBackgroundWhereItsAlphaIsBelowTheCutoffInEveryEngine) {
  const PreparedScene scene(quad_scene(glowing(AlphaMode::Mask, 1.0f, true)));
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    const RenderSettings settings = settings_for(engine);
    const TileBuffer image = test::render_full(scene, settings);
    int covered = 0, cut = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        // Where each engine's one sample lies: the centre, or the path tracer's jitter.
        glm::vec2 offset(0.5f);
        if (engine == EngineKind::Path) {
          const SampleKey key{frame_seed(settings.seed, settings.frame),
                              static_cast<std::uint64_t>(y) * kWidth + static_cast<std::uint64_t>(x), 0};
          offset = {sample_uniform(key, 0), sample_uniform(key, 1)};
        }
        glm::vec2 uv;
        const Ray ray = scene.scene().camera.primary_ray(static_cast<float>(x) + offset.x,
                                                         static_cast<float>(y) + offset.y, kWidth, kHeight);
        if (!ray_uv(ray, uv)) continue;
        const float alpha = bilinear_alpha(uv);
        if (std::fabs(alpha - 0.5f) < 0.1f) continue;  // too near a texel's edge to call
        const glm::vec3 expected = alpha >= 0.5f ? kGlow : kBackground;
        (alpha >= 0.5f ? covered : cut) += 1;
        const glm::vec3 got(image.rgba(x, y));
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(got[c], expected[c], 1e-4f) << to_string(engine) << " pixel " << x << "," << y << " alpha " << alpha;
      }
    EXPECT_GT(covered, 200) << to_string(engine);
    EXPECT_GT(cut, 200) << to_string(engine);
  }
}

// Constant alpha 0.3, blended: each engine's samples see the glow behind 30% of them (the ray
// engines by a hash of the ray, the rasterizer by a hash of the fragment), so the mean over the
// square's pixels is 0.3 of the glow plus 0.7 of the background.
TEST(AlphaCutout, ABlendedQuadStopsAShareOfTheSamplesEqualToItsAlpha) {
  const PreparedScene scene(quad_scene(glowing(AlphaMode::Blend, 0.3f, false)));
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    const TileBuffer image = test::render_full(scene, settings_for(engine, 64));
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        glm::vec2 uv;
        if (!ray_uv(scene.scene().camera.primary_ray(x + 0.5f, y + 0.5f, kWidth, kHeight), uv)) continue;
        sum += image.rgba(x, y).x;  // red: kGlow's 1 where stopped, the background's 0 where not
        ++n;
      }
    ASSERT_GT(n, 500);
    // 64 samples on each of n pixels: a binomial share's standard error is under 0.003.
    EXPECT_NEAR(sum / n, 0.3, 0.012) << to_string(engine);
  }
}

// The hashes that decide a blended surface's samples are keyed by what is rendered (the ray, or
// the pixel, sample position and depth), never by the tiles or threads: bit-identical images.
TEST(AlphaCutout, BlendedAndMaskedSurfacesGiveTheSameBitsAcrossTilesAndThreads) {
  Scene base = quad_scene(glowing(AlphaMode::Blend, 0.4f, false));
  Scene masked = quad_scene(glowing(AlphaMode::Mask, 1.0f, true));
  masked.objects[0].model_to_world = glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, 0.2f, -0.5f));
  base.objects.push_back(masked.objects[0]);
  const PreparedScene scene(base);
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    RenderSettings whole = settings_for(engine, 8), tiled = whole;
    whole.tile_size = 64;
    whole.threads = 1;
    tiled.tile_size = 7;
    tiled.threads = 3;
    const TileBuffer a = render_frame(scene, whole), b = render_frame(scene, tiled);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) ASSERT_EQ(a.rgba(x, y), b.rgba(x, y)) << to_string(engine) << " " << x << "," << y;
  }
}

// A floor under a point light and an area light, with a square between them and the camera: cut
// out everywhere (alpha 0, masked), the square changes no pixel in any engine, its shadows
// included; opaque (alpha 1), it does.
TEST(AlphaCutout, AnOccluderCutOutEverywhereChangesNoPixelShadowsIncluded) {
  const auto scene_with = [](std::optional<float> occluder_alpha) {
    Scene s;
    Material floor;
    floor.diffuse = glm::vec3(0.7f);
    s.objects.push_back(test::object_of(test::make_quad({-3, -1, 3}, {3, -1, 3}, {3, -1, -3}, {-3, -1, -3}),
                                        glm::mat4(1.0f), floor));
    Material lamp;
    lamp.emission = glm::vec3(8.0f);
    s.objects.push_back(test::object_of(test::make_quad({-0.5f, 2, -0.5f}, {0.5f, 2, -0.5f}, {0.5f, 2, 0.5f}, {-0.5f, 2, 0.5f}),
                                        glm::mat4(1.0f), lamp));
    if (occluder_alpha) {
      Material card;
      card.diffuse = glm::vec3(0.9f, 0.2f, 0.2f);
      card.alpha_mode = AlphaMode::Mask;
      card.alpha = *occluder_alpha;
      s.objects.push_back(test::object_of(test::make_quad({-1, 0.5f, 1}, {1, 0.5f, 1}, {1, 0.5f, -1}, {-1, 0.5f, -1}),
                                          glm::mat4(1.0f), card));
    }
    Light bulb;
    bulb.position = {0.2f, 3.0f, 0.1f};
    bulb.intensity = glm::vec3(6.0f);
    s.lights.push_back(bulb);
    s.camera.position = {0.0f, 3.0f, 4.0f};
    s.camera.target = {0.0f, -1.0f, 0.0f};
    return s;
  };
  const PreparedScene bare(scene_with(std::nullopt)), cut(scene_with(0.0f)), opaque(scene_with(1.0f));
  EXPECT_FALSE(has_cutouts(bare));
  EXPECT_TRUE(has_cutouts(cut));
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    RenderSettings settings = settings_for(engine, 4);
    settings.max_depth = 3;
    const TileBuffer a = test::render_full(bare, settings), b = test::render_full(cut, settings),
                     c = test::render_full(opaque, settings);
    int differ = 0, shaded = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        ASSERT_EQ(a.rgba(x, y), b.rgba(x, y)) << to_string(engine) << " pixel " << x << "," << y;
        differ += a.rgba(x, y) != c.rgba(x, y);
        shaded += a.rgba(x, y).x > 0.0f;
      }
    EXPECT_GT(shaded, kWidth * kHeight / 2) << to_string(engine);
    EXPECT_GT(differ, kWidth * kHeight / 20) << to_string(engine);  // the card and its shadow
  }
}

}  // namespace
}  // namespace farm
