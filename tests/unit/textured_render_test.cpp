// Textures through every engine, checked without a second renderer: a tilted quad whose only light
// is its own emission texture, rendered by each engine and compared pixel by pixel with the
// texture resampled here along the same camera rays (the plane intersected and the texture
// filtered by this file's own code). A wrong v direction, uvs interpolated without perspective,
// a corner's uv on the wrong vertex or a sampler off by half a texel each move every pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/trigonometric.hpp>
#include <memory>
#include <vector>

#include "renderer/engine.h"
#include "renderer/texture/material_textures.h"
#include "renderer/trace/sampler.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

constexpr int kSide = 8;  // texels on a side
constexpr int kWidth = 48, kHeight = 40;

glm::vec4 texel_colour(int i, int j) {
  return {static_cast<float>(i) / kSide, static_cast<float>(j) / kSide, static_cast<float>((i * 3 + j * 5) % 7) / 7.0f,
          1.0f};
}

// Bilinear filtering with repeat wrapping, texel centres at (i + 0.5) / side: Texture::sample's
// rule for level 0, written again from its definition.
glm::vec3 bilinear(glm::vec2 uv) {
  const float x = uv.x * kSide - 0.5f, y = uv.y * kSide - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const auto at = [](int i, int j) { return glm::vec3(texel_colour(((i % kSide) + kSide) % kSide, ((j % kSide) + kSide) % kSide)); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

struct TexturedQuad {
  glm::vec3 corner[4] = {{-1.0f, -0.8f, 0.3f}, {1.1f, -0.9f, -0.4f}, {0.9f, 0.9f, -0.2f}, {-1.2f, 0.8f, 0.5f}};
  // uv of each corner: v grows downward in the image, so the top corners have v = 0.
  glm::vec2 uv[4] = {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}};
};

Scene textured_quad_scene(const TexturedQuad& q) {
  Model model = test::make_quad(q.corner[0], q.corner[1], q.corner[2], q.corner[3]);
  model.meshes[0].uvs = {q.uv[0], q.uv[1], q.uv[2], q.uv[3]};
  std::vector<glm::vec4> texels;
  for (int j = 0; j < kSide; ++j)
    for (int i = 0; i < kSide; ++i) texels.push_back(texel_colour(i, j));
  auto textures = std::make_shared<MaterialTextures>();
  textures->emission.texture = std::make_shared<const Texture>(kSide, kSide, std::move(texels));
  textures->emission.sampler.mipmaps = false;  // level 0 at any footprint: what bilinear() reads
  Material m;
  m.diffuse = glm::vec3(0.0f);
  m.ambient = glm::vec3(0.0f);
  m.emission = glm::vec3(1.0f);
  m.emission_sides = EmissionSides::Both;
  m.textures = textures;
  Scene scene;
  scene.objects.push_back(test::object_of(model, glm::mat4(1.0f), m));
  scene.ambient = glm::vec3(0.0f);
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0.3f, 0.2f, 4.0f};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  return scene;
}

// Where the ray meets the quad's triangle (a, b, c) as uv, by solving the plane and barycentrics
// in double precision; false when it misses or lands within `margin` of an edge.
bool ray_uv(const Ray& ray, const TexturedQuad& q, int a, int b, int c, double margin, glm::vec2& out) {
  const glm::dvec3 o(ray.origin), d(ray.direction), p0(q.corner[a]), p1(q.corner[b]), p2(q.corner[c]);
  const glm::dvec3 n = glm::cross(p1 - p0, p2 - p0);
  const double t = glm::dot(p0 - o, n) / glm::dot(d, n);
  const glm::dvec3 p = o + t * d;
  const double area = glm::dot(n, n);
  const double w1 = glm::dot(glm::cross(p - p0, p2 - p0), n) / area;   // weight of b
  const double w2 = glm::dot(glm::cross(p1 - p0, p - p0), n) / area;   // weight of c
  const double w0 = 1.0 - w1 - w2;
  if (!(t > 0.0) || w0 < margin || w1 < margin || w2 < margin) return false;
  out = glm::vec2(w0 * glm::dvec2(q.uv[a]) + w1 * glm::dvec2(q.uv[b]) + w2 * glm::dvec2(q.uv[c]));
  return true;
}

// Compares every pixel whose ray (through pixel offset `offset(x, y)`) lands well inside the quad.
template <typename Offset>
void expect_texture_seen(const Scene& scene, const TexturedQuad& q, const TileBuffer& image, Offset&& offset,
                         float tolerance) {
  int compared = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const glm::vec2 o = offset(x, y);
      const Ray ray = scene.camera.primary_ray(static_cast<float>(x) + o.x, static_cast<float>(y) + o.y, kWidth, kHeight);
      glm::vec2 uv;
      if (!ray_uv(ray, q, 0, 1, 2, 2e-3, uv) && !ray_uv(ray, q, 0, 2, 3, 2e-3, uv)) continue;
      const glm::vec3 expected = bilinear(uv);
      const glm::vec3 got(image.rgba(x, y));
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(got[c], expected[c], tolerance) << "pixel " << x << "," << y << " channel " << c << " uv " << uv.x
                                                    << "," << uv.y;
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, kWidth * kHeight / 4);  // the quad fills much of the frame
}

RenderSettings settings_for(EngineKind engine) {
  RenderSettings s = test::raster_settings(kWidth, kHeight);
  s.engine = engine;
  s.spp = 1;
  s.max_depth = 0;
  return s;
}

TEST(TexturedRender, WhittedSeesTheEmissionTextureAlongItsCameraRays) {
  const TexturedQuad q;
  const PreparedScene scene(textured_quad_scene(q));
  const TileBuffer image = test::render_full(scene, settings_for(EngineKind::Whitted));
  expect_texture_seen(scene.scene(), q, image, [](int, int) { return glm::vec2(0.5f); }, 1e-4f);
}

TEST(TexturedRender, TheRasterizerInterpolatesUvsWithPerspective) {
  const TexturedQuad q;
  const PreparedScene scene(textured_quad_scene(q));
  const TileBuffer image = test::render_full(scene, settings_for(EngineKind::Raster));
  // Fixed-point snapping moves a vertex by up to 1/256 pixel: a few thousandths of a texel.
  expect_texture_seen(scene.scene(), q, image, [](int, int) { return glm::vec2(0.5f); }, 2e-3f);
}

TEST(TexturedRender, ThePathTracerSeesTheEmissionTextureAtEachJitteredSample) {
  const TexturedQuad q;
  const PreparedScene scene(textured_quad_scene(q));
  const RenderSettings settings = settings_for(EngineKind::Path);
  const TileBuffer image = test::render_full(scene, settings);
  // One sample per pixel, at the position the path tracer's sampler puts it (sampler.h).
  expect_texture_seen(
      scene.scene(), q, image,
      [&](int x, int y) {
        const SampleKey key{frame_seed(settings.seed, settings.frame),
                            static_cast<std::uint64_t>(y) * kWidth + static_cast<std::uint64_t>(x), 0};
        return glm::vec2(sample_uniform(key, 0), sample_uniform(key, 1));
      },
      1e-4f);
}

// The path tracer's light sampling reads the emission texture where it picks a point: a white
// floor under the textured quad receives what the texture emits, whether the light is found by
// BSDF sampling alone or by next-event estimation with MIS (both unbiased, so their means agree).
TEST(TexturedRender, NextEventEstimationReadsTheEmissionTextureAsBsdfSamplingDoes) {
  const TexturedQuad q;
  Scene base = textured_quad_scene(q);
  base.objects[0].materials[0].emission = glm::vec3(5.0f);
  Material floor;
  floor.diffuse = glm::vec3(0.8f);
  base.objects.push_back(test::object_of(test::make_quad({-3, -2, 3}, {3, -2, 3}, {3, -2, -3}, {-3, -2, -3}),
                                         glm::mat4(1.0f), floor));
  base.camera.position = {0.0f, 1.0f, 5.0f};
  base.camera.target = {0.0f, -2.0f, 0.0f};
  const PreparedScene scene(base);
  RenderSettings settings = settings_for(EngineKind::Path);
  settings.max_depth = 1;
  settings.spp = 256;
  const auto floor_mean = [&](LightSampling sampling) {
    settings.light_sampling = sampling;
    const TileBuffer image = test::render_full(scene, settings);
    glm::dvec3 sum(0.0);
    for (int y = kHeight * 3 / 4; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) sum += glm::dvec3(glm::vec3(image.rgba(x, y)));
    return sum / static_cast<double>(kWidth * (kHeight - kHeight * 3 / 4));
  };
  const glm::dvec3 nee = floor_mean(LightSampling::NeeMis), bsdf = floor_mean(LightSampling::BsdfOnly);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(nee[c], 0.005) << c;
    EXPECT_NEAR(nee[c], bsdf[c], 0.05 * bsdf[c] + 1e-3) << "channel " << c;
  }
}

// A textured material on a mesh without texture coordinates (an OBJ whose MTL names a map but
// whose faces give no vt) reads the texture at uv (0, 0) everywhere, in every engine, and renders.
TEST(TexturedRender, ATexturedMaterialOnAMeshWithoutUvsReadsTheTextureAtTheOrigin) {
  const TexturedQuad q;
  Scene base = textured_quad_scene(q);
  Model bare = test::make_quad(q.corner[0], q.corner[1], q.corner[2], q.corner[3]);
  base.objects[0].model = std::make_shared<const Model>(std::move(bare));
  const glm::vec3 expected = bilinear(glm::vec2(0.0f));
  const PreparedScene scene(base);
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    const TileBuffer image = test::render_full(scene, settings_for(engine));
    const glm::vec4 centre = image.rgba(kWidth / 2, kHeight / 2);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre[c], expected[c], 1e-5f) << to_string(engine) << " channel " << c;
  }
}

// The square [-1, 1]^2 on z = 0 facing +z, its uvs once across (u along +x, v falling along +y)
// and its tangents made from them; and a material of diffuse `kd` whose one-texel normal map holds
// `tangent_space`, in a scene with no ambient light and a black background.
struct NormalMappedSquare {
  Model model;
  Material material;
};
NormalMappedSquare normal_mapped_square(const glm::vec3& tangent_space, float kd) {
  NormalMappedSquare out{test::make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}), {}};
  Mesh& mesh = out.model.meshes[0];
  mesh.uvs = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  generate_tangents(mesh);
  auto textures = std::make_shared<MaterialTextures>();
  textures->normal.texture =
      std::make_shared<const Texture>(1, 1, std::vector<glm::vec4>{glm::vec4(0.5f * (tangent_space + 1.0f), 1.0f)});
  out.material.diffuse = glm::vec3(kd);
  out.material.ambient = glm::vec3(0.0f);
  out.material.textures = textures;
  return out;
}

// A normal map on a plane facing +z, its one texel the tangent-space normal (sin a, 0, cos a):
// with the tangent made from the uvs (u grows along +x), the shading normal tilts towards +x by
// a, so a directional light from (1, 0, 1) lights it by kd cos(45 - a) instead of kd cos 45, on
// every pixel of the plane, in whitted and in the rasterizer alike. A tangent frame turned the
// wrong way, a map read as sRGB or not remapped to [-1, 1], or a bitangent on the wrong side of a
// mirrored object each move the value.
TEST(TexturedRender, ANormalMapTiltsTheShadingNormalInTheTangentFrame) {
  const float a = glm::radians(30.0f);
  const glm::vec3 tangent_space(std::sin(a), 0.0f, std::cos(a));
  for (const bool mirrored : {false, true}) {
    const NormalMappedSquare square = normal_mapped_square(tangent_space, 0.8f);
    const Mesh& mesh = square.model.meshes[0];
    ASSERT_EQ(mesh.tangents.size(), 4u);
    for (const glm::vec4& t : mesh.tangents) EXPECT_EQ(t, glm::vec4(1, 0, 0, 1));  // u along +x, v falling along +y
    Scene scene;
    // Mirrored in x: the plane and its tilt mirror too, so the light must come from -x to see the
    // same angle.
    const glm::mat4 to_world = mirrored ? glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1)) : glm::mat4(1.0f);
    scene.objects.push_back(test::object_of(square.model, to_world, square.material));
    scene.ambient = glm::vec3(0.0f);
    scene.background = glm::vec3(0.0f);
    scene.camera.position = {0.0f, 0.0f, 3.0f};
    scene.camera.target = {0.0f, 0.0f, 0.0f};
    const glm::vec3 to_light = glm::normalize(glm::vec3(mirrored ? -1.0f : 1.0f, 0.0f, 1.0f));
    scene.lights.push_back(Light{Light::Kind::Directional, {}, -to_light, glm::vec3(1.0f)});
    const float expected = 0.8f * std::cos(glm::radians(45.0f) - a);
    const PreparedScene prepared(scene);
    for (const EngineKind engine : {EngineKind::Whitted, EngineKind::Raster}) {
      const TileBuffer image = test::render_full(prepared, settings_for(engine));
      const glm::vec4 centre = image.rgba(kWidth / 2, kHeight / 2);
      EXPECT_NEAR(centre.x, expected, 1e-4f) << to_string(engine) << (mirrored ? " mirrored" : "");
      EXPECT_NEAR(image.rgba(kWidth / 2 + 5, kHeight / 2 - 4).y, expected, 1e-4f) << to_string(engine);
    }
  }
}

// A normal map bent so far that a grazing viewer lies below it: the tangent-space normal
// (0.8, 0, 0.6) on a plane facing +z is bent towards +x, and the camera looks from low on the -x
// side. Turned around (as a plain normal seen from behind is) it would point into the plane and a
// light above would be behind it: black. Reflected about the plane's normal it is (-0.8, 0, 0.6),
// facing the viewer, and a directional light from (-0.6, 0, 0.8) lights it by 0.96: kd * 0.96 in
// the rasterizer and Whitted, kd / pi * 0.96 in the path tracer (direct light only), on every
// pixel of the plane, and the rasterizer's and Whitted's normal AOV is the reflected normal.
TEST(TexturedRender, ANormalMapBentAwayFromAGrazingViewerIsReflectedAboutThePlaneNotTurnedIntoIt) {
  const NormalMappedSquare square = normal_mapped_square(glm::vec3(0.8f, 0.0f, 0.6f), 0.5f);
  Scene scene;
  scene.objects.push_back(test::object_of(square.model, glm::mat4(1.0f), square.material));
  scene.ambient = glm::vec3(0.0f);
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {-3.0f, 0.0f, 1.0f};
  scene.camera.target = {0.0f, 0.0f, 0.0f};
  scene.camera.up = {0.0f, 0.0f, 1.0f};
  scene.lights.push_back(Light{Light::Kind::Directional, {}, -glm::vec3(-0.6f, 0.0f, 0.8f), glm::vec3(1.0f)});
  const PreparedScene prepared(scene);
  const glm::vec3 reflected(-0.8f, 0.0f, 0.6f);
  for (const EngineKind engine : {EngineKind::Raster, EngineKind::Whitted, EngineKind::Path}) {
    RenderSettings settings = settings_for(engine);
    settings.aovs.normal = true;
    if (engine == EngineKind::Path) {
      settings.spp = 4;
      settings.max_depth = 1;
    }
    const TileBuffer image = test::render_full(prepared, settings);
    const float expected = 0.5f * 0.96f / (engine == EngineKind::Path ? glm::pi<float>() : 1.0f);
    int plane = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        if (image.rgba(x, y).w < 1.0f) continue;
        ++plane;
        ASSERT_NEAR(image.rgba(x, y).x, expected, 1e-4f) << to_string(engine) << " at " << x << "," << y;
        if (engine == EngineKind::Path) continue;  // its normal AOV is the surface's, not the frame's
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(image.normal(x, y)[c], reflected[c], 1e-4f) << to_string(engine);
      }
    EXPECT_GT(plane, 50) << to_string(engine);
  }
}

// The path tracer's direct light on a normal-mapped square against the integral done here: a
// 0.5 x 0.5 lamp (radiance 12, shining down) hangs 1.6 above the square, off to a corner; the
// map tilts every normal to (0.3, 0.2, 1). With direct light only (max_depth 1: the lamp by
// next-event estimation and by BSDF sampling, weighted by MIS) each pixel is kd / pi times the
// lamp's radiance integrated over it with the bent normal's cosine, which this test sums over a
// 64 x 64 grid of lamp points. (Mitsuba 3's normalmap adapter came out 0.7% under this integral
// in a set-up like this; issue #35's notes.) A tangent frame the wrong way round, the map's Y read
// upside down or a cosine taken about the unbent normal each move the sum by many errors.
TEST(TexturedRender, APathTracedNormalMappedSquareUnderALampMatchesItsDirectLightIntegral) {
  const glm::vec3 tangent_space = glm::normalize(glm::vec3(0.3f, 0.2f, 1.0f));
  const NormalMappedSquare square = normal_mapped_square(tangent_space, 0.7f);
  Material lamp;
  lamp.diffuse = glm::vec3(0.0f);
  lamp.emission = glm::vec3(12.0f);
  Scene scene;
  scene.objects.push_back(test::object_of(square.model, glm::mat4(1.0f), square.material));
  const float z = 1.6f;  // corners counter-clockwise seen from below: it shines down
  scene.objects.push_back(test::object_of(
      test::make_quad({-1.25f, 0.3f, z}, {-1.25f, 0.8f, z}, {-0.75f, 0.8f, z}, {-0.75f, 0.3f, z}), glm::mat4(1.0f),
      lamp));
  scene.ambient = glm::vec3(0.0f);
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0.3f, 0.2f, 4.0f};
  scene.camera.target = {0.3f, 0.2f, 0.0f};
  scene.camera.fov_y_degrees = 30.0f;
  const PreparedScene prepared(scene);
  RenderSettings settings = test::raster_settings(32, 24);
  settings.engine = EngineKind::Path;
  settings.spp = 256;
  settings.max_depth = 1;
  settings.aovs.variance = true;
  const TileBuffer image = test::render_full(prepared, settings);

  // The bent normal: the square's tangent frame is +x, +y (v falls along +y), +z.
  const glm::dvec3 bent = glm::normalize(glm::dvec3(tangent_space));
  constexpr int kGrid = 64;
  const auto direct = [&](const glm::dvec3& p) {
    double sum = 0.0;
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j) {
        const glm::dvec3 q(-1.25 + 0.5 * (i + 0.5) / kGrid, 0.3 + 0.5 * (j + 0.5) / kGrid, z);
        const glm::dvec3 d = q - p;
        const double r2 = glm::dot(d, d);
        const glm::dvec3 w = d / std::sqrt(r2);
        sum += std::max(0.0, glm::dot(w, bent)) * w.z / r2;  // w.z: the cosine at the lamp, facing down
      }
    return 0.7 / glm::pi<double>() * 12.0 * sum * (0.25 / (kGrid * kGrid));
  };
  double ours = 0.0, expected = 0.0, variance = 0.0;
  int pixels = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      const Ray ray = scene.camera.primary_ray(static_cast<float>(x) + 0.5f, static_cast<float>(y) + 0.5f, 32, 24);
      const double t = static_cast<double>(-ray.origin.z / ray.direction.z);
      const glm::dvec3 p = glm::dvec3(ray.origin) + t * glm::dvec3(ray.direction);
      // On the square, not behind the lamp, and away from the square's edges.
      if (std::fabs(p.x) > 0.9 || std::fabs(p.y) > 0.9) continue;
      const glm::dvec3 at_lamp =
          glm::dvec3(ray.origin) + static_cast<double>((z - ray.origin.z) / ray.direction.z) * glm::dvec3(ray.direction);
      if (at_lamp.x > -1.35 && at_lamp.x < -0.65 && at_lamp.y > 0.2 && at_lamp.y < 0.9) continue;
      ours += image.rgba(x, y).x;
      expected += direct(p);
      variance += image.variance(x, y).x;
      ++pixels;
    }
  ASSERT_GT(pixels, 300);
  const double error = std::sqrt(variance);
  std::printf("normal-mapped square: %d pixels, mean %.6f, integral %.6f (%+.3f%%, %.2f standard errors)\n", pixels,
              ours / pixels, expected / pixels, 100.0 * (ours / expected - 1.0), (ours - expected) / error);
  // Four standard errors, and 0.05% for a pixel's footprint (the integral is taken at its centre).
  EXPECT_LT(std::fabs(ours - expected), 4.0 * error + 0.0005 * expected);
}

}  // namespace
}  // namespace farm
