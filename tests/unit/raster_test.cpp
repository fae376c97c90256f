#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "renderer/engine.h"
#include "renderer/raster/raster_frame.h"
#include "renderer/render_frame.h"
#include "renderer/scene/transform.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

using test::make_box;
using test::make_grid;
using test::make_quad;
using test::make_sphere;
using test::object_of;
using test::raster_settings;
using test::render_full;

AovSet depth_and_normal() {
  AovSet a;
  a.depth = true;
  a.normal = true;
  return a;
}

TEST(RasterPerspective, SlantedQuadDepthMatchesAnalyticRayPlaneIntersection) {
  Scene scene;
  // A quad receding steeply from the camera: affine (screen-space) interpolation of depth would
  // be off by tens of percent across it.
  const glm::vec3 a{-1, -1, 1}, b{1, -1, 1}, c{1, 1, -6}, d{-1, 1, -6};
  scene.objects.push_back(object_of(make_quad(a, b, c, d)));
  scene.camera.position = {0, 0, 3};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 60;
  scene.camera.near = 0.1f;
  scene.camera.far = 50;
  const PreparedScene prepared(std::move(scene));
  const RenderSettings settings = raster_settings(96, 96, depth_and_normal());
  const TileBuffer image = render_full(prepared, settings);

  const glm::vec3 n = glm::normalize(glm::cross(b - a, c - a));
  int covered = 0;
  for (int y = 0; y < settings.height; ++y) {
    for (int x = 0; x < settings.width; ++x) {
      if (image.rgba(x, y).w == 0.0f) continue;
      ++covered;
      const Ray ray = prepared.scene().camera.primary_ray(x + 0.5f, y + 0.5f, settings.width,
                                                          settings.height);
      const float t = glm::dot(a - ray.origin, n) / glm::dot(ray.direction, n);
      ASSERT_NEAR(image.depth(x, y), t, 1e-3f * t) << "pixel " << x << "," << y;
      const glm::vec3 facing = glm::dot(n, ray.direction) < 0 ? n : -n;
      ASSERT_NEAR(glm::dot(image.normal(x, y), facing), 1.0f, 1e-5f);
    }
  }
  EXPECT_GT(covered, 96 * 96 / 4);
}

TEST(RasterNormalMatrix, NonUniformScaleKeepsNormalsPerpendicularToSurfaces) {
  const glm::mat4 m = glm::scale(
      glm::rotate(glm::translate(glm::mat4(1.0f), {1, 2, 3}), 0.7f, glm::normalize(glm::vec3(1, 2, 0.5f))),
      {1.0f, 5.0f, 0.2f});
  const glm::vec3 p0{0.3f, -0.2f, 0.5f}, p1{1.0f, 0.4f, -0.3f}, p2{-0.5f, 0.9f, 0.2f};
  const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
  const glm::vec3 e1 = glm::vec3(m * glm::vec4(p1 - p0, 0.0f));
  const glm::vec3 e2 = glm::vec3(m * glm::vec4(p2 - p0, 0.0f));
  const glm::vec3 n_world = glm::normalize(normal_matrix(m) * n);
  EXPECT_NEAR(glm::dot(n_world, glm::normalize(e1)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(n_world, glm::normalize(e2)), 0.0f, 1e-5f);
  // The naive transform (by the model matrix itself) is visibly wrong under this scale.
  const glm::vec3 n_naive = glm::normalize(glm::mat3(m) * n);
  EXPECT_GT(std::fabs(glm::dot(n_naive, glm::normalize(e1))), 0.05f);
}

// Distance along the ray (in units of its direction) to where it leaves the box, from inside.
float exit_distance(const Ray& ray, glm::vec3 lo, glm::vec3 hi) {
  float t = INFINITY;
  for (int axis = 0; axis < 3; ++axis) {
    const float d = ray.direction[axis];
    if (d > 0) t = std::min(t, (hi[axis] - ray.origin[axis]) / d);
    if (d < 0) t = std::min(t, (lo[axis] - ray.origin[axis]) / d);
  }
  return t;
}

TEST(RasterClipping, CameraInsideABoxSeesEveryWallAtTheRightDepth) {
  // Triangles of every wall cross the near plane and pass behind the camera: they must be
  // clipped in homogeneous space, not divided by w <= 0.
  const glm::vec3 lo{-2, -2, -2}, hi{2, 2, 2};
  Scene scene;
  scene.objects.push_back(object_of(make_box(lo, hi)));
  scene.camera.position = {0.3f, 0.2f, 0.1f};
  scene.camera.target = {1.0f, 0.5f, -2.0f};
  scene.camera.fov_y_degrees = 100;
  scene.camera.near = 0.05f;
  scene.camera.far = 100;
  const PreparedScene prepared(std::move(scene));
  const RenderSettings settings = raster_settings(80, 60, depth_and_normal());
  const TileBuffer image = render_full(prepared, settings);
  for (int y = 0; y < settings.height; ++y) {
    for (int x = 0; x < settings.width; ++x) {
      ASSERT_EQ(image.rgba(x, y).w, 1.0f) << "hole at " << x << "," << y;
      const Ray ray = prepared.scene().camera.primary_ray(x + 0.5f, y + 0.5f, settings.width,
                                                          settings.height);
      const float t = exit_distance(ray, lo, hi);
      ASSERT_NEAR(image.depth(x, y), t, 2e-3f * t) << "pixel " << x << "," << y;
    }
  }
}

TEST(RasterCoverage, SharedEdgesOfADenseGridLeaveNoCracks) {
  Scene scene;
  scene.objects.push_back(object_of(make_grid(37), glm::scale(glm::mat4(1.0f), {4, 4, 1})));
  scene.camera.position = {0.4f, -1.3f, 2.0f};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 50;
  const PreparedScene prepared(std::move(scene));
  const TileBuffer image = render_full(prepared, raster_settings(200, 150));
  for (int y = 0; y < 150; ++y)
    for (int x = 0; x < 200; ++x) ASSERT_EQ(image.rgba(x, y).w, 1.0f) << x << "," << y;
}

TEST(RasterShading, CentrePixelMatchesBlinnPhongComputedByHand) {
  Material m;
  m.ambient = {1, 1, 1};
  m.diffuse = {0.6f, 0.4f, 0.2f};
  m.specular = {0.5f, 0.5f, 0.5f};
  m.shininess = 20;
  Scene scene;
  scene.objects.push_back(object_of(make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}),
                                    glm::mat4(1.0f), m));
  scene.camera.position = {0, 0, 4};
  scene.camera.target = {0, 0, 0};
  scene.lights.push_back(Light{Light::Kind::Point, {0.5f, 0.5f, 1.0f}, {}, glm::vec3(3.0f)});
  scene.ambient = glm::vec3(0.1f);
  const PreparedScene prepared(std::move(scene));
  const TileBuffer image = render_full(prepared, raster_settings(65, 65));

  // The centre pixel's ray hits the origin; work the formula out independently.
  const glm::vec3 p{0, 0, 0}, n{0, 0, 1}, v{0, 0, 1};
  const glm::vec3 to_light = glm::vec3(0.5f, 0.5f, 1.0f) - p;
  const float r2 = glm::dot(to_light, to_light);
  const glm::vec3 l = glm::normalize(to_light);
  const glm::vec3 h = glm::normalize(l + v);
  const glm::vec3 expected = m.ambient * 0.1f + (3.0f / r2) * (m.diffuse * glm::dot(n, l) +
                                                               m.specular * std::pow(glm::dot(n, h), 20.0f));
  const glm::vec4 got = image.rgba(32, 32);
  EXPECT_NEAR(got.x, expected.x, 1e-4f);
  EXPECT_NEAR(got.y, expected.y, 1e-4f);
  EXPECT_NEAR(got.z, expected.z, 1e-4f);
  EXPECT_EQ(got.w, 1.0f);
  // A corner pixel sees past the quad: background colour, zero coverage.
  EXPECT_EQ(image.rgba(0, 0), glm::vec4(prepared.scene().background, 0.0f));
}

TEST(RasterDepth, NearerSurfaceWinsWhateverTheDrawOrder) {
  Material red, green;
  red.diffuse = {1, 0, 0};
  green.diffuse = {0, 1, 0};
  for (bool near_first : {true, false}) {
    Scene scene;
    const Model quad = make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0});
    SceneObject near_obj = object_of(quad, glm::translate(glm::mat4(1.0f), {0, 0, 0.5f}), red);
    SceneObject far_obj = object_of(quad, glm::mat4(1.0f), green);
    scene.objects.push_back(near_first ? near_obj : far_obj);
    scene.objects.push_back(near_first ? far_obj : near_obj);
    scene.camera.position = {0, 0, 3};
    scene.camera.target = {0, 0, 0};
    scene.lights.push_back(Light{Light::Kind::Point, {0, 0, 3}, {}, glm::vec3(10.0f)});
    scene.ambient = glm::vec3(0.0f);
    const PreparedScene prepared(std::move(scene));
    const TileBuffer image = render_full(prepared, raster_settings(33, 33));
    const glm::vec4 c = image.rgba(16, 16);
    EXPECT_GT(c.x, 0.5f) << "near_first=" << near_first;
    EXPECT_EQ(c.y, 0.0f) << "near_first=" << near_first;
  }
}

Scene busy_scene() {
  Scene scene;
  Material shiny;
  shiny.diffuse = {0.7f, 0.3f, 0.2f};
  shiny.specular = glm::vec3(0.4f);
  shiny.shininess = 40;
  // Two identical quads, first and last in scene order, so every pixel of them is an exact depth
  // tie that only scene order can decide; the sphere between them puts them in different
  // set-up chunks.
  Material first_colour, last_colour;
  first_colour.diffuse = {0.9f, 0.1f, 0.1f};
  last_colour.diffuse = {0.1f, 0.1f, 0.9f};
  const Model tie_quad = make_quad({-2, -1, -2.5f}, {2, -1, -2.5f}, {2, 2, -2.5f}, {-2, 2, -2.5f});
  scene.objects.push_back(object_of(tie_quad, glm::mat4(1.0f), first_colour));
  // Over 8192 triangles, so set-up is split into several chunks that must merge in order.
  scene.objects.push_back(object_of(make_sphere(80, 100), glm::scale(glm::mat4(1.0f), {1.0f, 1.4f, 0.8f}), shiny));
  // A floor that passes under and behind the camera: its triangles are clipped at the near plane.
  scene.objects.push_back(object_of(make_box({-6, -1.6f, -6}, {6, -1.2f, 6})));
  scene.objects.push_back(object_of(make_grid(9), glm::translate(glm::mat4(1.0f), {0.5f, 0.2f, -1.5f})));
  scene.objects.push_back(object_of(tie_quad, glm::mat4(1.0f), last_colour));
  scene.camera.position = {2.5f, 1.5f, 3.5f};
  scene.camera.target = {0, 0, 0};
  scene.lights.push_back(Light{Light::Kind::Point, {3, 4, 2}, {}, glm::vec3(20.0f)});
  scene.lights.push_back(Light{Light::Kind::Directional, {}, {-1, -1, 0}, glm::vec3(0.3f)});
  return scene;
}

bool same_bits(const TileBuffer& a, const TileBuffer& b) {
  if (!(a.rect() == b.rect())) return false;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      if (std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) != 0) return false;
      const float da = a.aovs().depth ? a.depth(x, y) : 0.0f, db = b.aovs().depth ? b.depth(x, y) : 0.0f;
      if (std::memcmp(&da, &db, sizeof(float)) != 0) return false;
      if (a.aovs().normal && std::memcmp(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3)) != 0)
        return false;
      if (a.aovs().variance && std::memcmp(&a.variance(x, y), &b.variance(x, y), sizeof(glm::vec3)) != 0)
        return false;
    }
  }
  return true;
}

TEST(RasterDepth, ExactTiesGoToTheTriangleEarlierInSceneOrder) {
  const PreparedScene prepared(busy_scene());
  RenderSettings settings = raster_settings(123, 77);
  settings.threads = 3;
  const TileBuffer image = render_frame(prepared, settings);
  int tie_pixels = 0;
  for (int y = 0; y < 77; ++y) {
    for (int x = 0; x < 123; ++x) {
      const glm::vec4 c = image.rgba(x, y);
      if (c.w == 1.0f && c.z > 2.0f * c.x) ADD_FAILURE() << "later quad won the tie at " << x << "," << y;
      if (c.w == 1.0f && c.x > 2.0f * c.z && c.x > 3.0f * c.y) ++tie_pixels;
    }
  }
  EXPECT_GT(tie_pixels, 100);  // the tied quads are in view
}

// The merge files each set-up chunk's triangles in their bins from their pixel bounds, the
// triangles clipping made between the ones kept whole, as they come in the scene. Meshes are
// numbered in scene order (a triangle's material index), so in every bin the numbers must never
// fall, and each entry must name a triangle that overlaps its bin.
TEST(RasterBinning, EveryBinListsItsTrianglesInSceneOrderClippedOnesInTheirPlace) {
  Scene scene;
  // One set-up chunk of whole and clipped triangles in turn: a floor under and behind the camera
  // (clipped at the near plane), a grid in view (whole), the floor again a little lower.
  scene.objects.push_back(object_of(make_box({-6, -1.6f, -6}, {6, -1.2f, 6})));
  scene.objects.push_back(object_of(make_grid(12), glm::scale(glm::mat4(1.0f), glm::vec3(3.0f))));
  scene.objects.push_back(object_of(make_box({-6, -1.9f, -6}, {6, -1.7f, 6})));
  scene.camera.position = {0.5f, 0.5f, 3.5f};
  scene.camera.target = {0, -0.5f, 0};
  const PreparedScene prepared(std::move(scene));
  const auto frame = raster::build_raster_frame(prepared, raster_settings(160, 120), nullptr, CancelFlag::never());
  ASSERT_FALSE(frame->clipped_triangles.empty()) << "no triangle was clipped";
  std::size_t mixed_bins = 0;
  for (int by = 0; by < frame->bins_y; ++by) {
    for (int bx = 0; bx < frame->bins_x; ++bx) {
      const std::size_t bin = static_cast<std::size_t>(by) * frame->bins_x + bx;
      const Rect rect = frame->bin_rect(bx, by);
      std::uint32_t last_mesh = 0;
      bool clipped = false, whole = false;
      for (std::uint32_t i = frame->bin_start[bin]; i < frame->bin_start[bin + 1]; ++i) {
        const std::uint32_t id = frame->bin_triangles[i];
        const raster::ScreenTriangle& t = frame->triangle(id);
        const std::uint32_t mesh = t.material & raster::kMaterialIndex;
        EXPECT_GE(mesh, last_mesh) << "bin " << bx << "," << by << " entry " << i - frame->bin_start[bin];
        last_mesh = mesh;
        EXPECT_TRUE(t.x0 < rect.x1 && t.x1 >= rect.x0 && t.y0 < rect.y1 && t.y1 >= rect.y0)
            << "a triangle filed in bin " << bx << "," << by << " that it does not overlap";
        (id & raster::kClippedTriangle ? clipped : whole) = true;
      }
      if (clipped && whole) ++mixed_bins;
    }
  }
  EXPECT_GT(mixed_bins, 5u) << "too few bins hold both clipped and whole triangles to tell their order";
}

TEST(RasterRenderTile, AnyTilingAndThreadCountGivesTheSameBitsAsOnePiece) {
  // Single-threaded, one tile: the reference.
  AovSet aovs = depth_and_normal();
  aovs.variance = true;  // zeros from the rasterizer, but they must merge like any channel
  RenderSettings settings = raster_settings(123, 77, aovs);
  settings.spp = 2;
  const PreparedScene reference_scene(busy_scene());
  const TileBuffer whole = render_full(reference_scene, settings);
  for (int threads : {1, 2, 3, 8}) {
    for (int tile_size : {8, 16, 32, 64, 128}) {
      // A fresh scene each time, so the frame set-up itself also runs on `threads` threads.
      const PreparedScene prepared(busy_scene());
      settings.tile_size = tile_size;
      settings.threads = threads;
      EXPECT_TRUE(same_bits(whole, render_frame(prepared, settings)))
          << "tile_size " << tile_size << " threads " << threads;
    }
  }
}

TEST(RasterRenderTile, SubRectangleGivesExactlyThosePixelsOfTheFullFrame) {
  const PreparedScene prepared(busy_scene());
  const RenderSettings settings = raster_settings(64, 48, depth_and_normal());
  const TileBuffer whole = render_full(prepared, settings);
  TileBuffer part;
  render_tile(prepared, settings, Rect{13, 9, 41, 30}, part);
  ASSERT_EQ(part.rect(), (Rect{13, 9, 41, 30}));
  TileBuffer cropped(part.rect(), part.aovs());
  cropped.paste(whole);
  EXPECT_TRUE(same_bits(part, cropped));
}

TEST(RasterRenderTile, PixelsOutsideTheImageAreNeverTouched) {
  const PreparedScene prepared(busy_scene());
  const RenderSettings settings = raster_settings(16, 16);
  TileBuffer out;
  render_tile(prepared, settings, Rect{-10, -10, 20, 20}, out);
  EXPECT_EQ(out.rect(), (Rect{0, 0, 16, 16}));
}

TEST(RasterSupersampling, EdgePixelsBlendAndInteriorKeepsItsColour) {
  Scene scene;
  scene.objects.push_back(object_of(make_quad({-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0})));
  scene.camera.position = {0, 0, 2};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 60;
  scene.lights.push_back(Light{Light::Kind::Directional, {}, {0, 0, -1}, glm::vec3(1.0f)});
  const PreparedScene prepared(std::move(scene));
  RenderSettings one = raster_settings(40, 40);
  RenderSettings many = one;
  many.spp = 16;
  const TileBuffer a = render_full(prepared, one), b = render_full(prepared, many);
  EXPECT_NEAR(b.rgba(20, 20).x, a.rgba(20, 20).x, 1e-5f);  // interior: identical shading
  int partial = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) partial += (b.rgba(x, y).w > 0.0f && b.rgba(x, y).w < 1.0f) ? 1 : 0;
  EXPECT_GT(partial, 20);  // the silhouette got fractional coverage
}

}  // namespace
}  // namespace farm
