// Meshes wholly outside the view are skipped before the rasterizer's vertex stage
// (renderer/raster/view_culling.h): only when every point of theirs is certainly beyond one plane
// of the frustum, so the frame's pixels, depths and normals keep every bit.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <random>

#include "renderer/raster/raster_frame.h"
#include "renderer/raster/view_culling.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

Camera looking_down_minus_z() {
  Camera camera;
  camera.position = {0, 0, 5};
  camera.target = {0, 0, 0};
  return camera;
}

glm::mat4 world_to_clip(const Camera& camera, float aspect) {
  return camera.projection_matrix(aspect) * camera.view_matrix();
}

AABB box(glm::vec3 min, glm::vec3 max) {
  AABB b;
  b.grow(min);
  b.grow(max);
  return b;
}

// The camera at z = 5 looks down -z with a 45-degree vertical field: at z = 0 the view spans
// about +-2.07 vertically (and as much horizontally at aspect 1).
TEST(ViewCulling, ABoxBeyondOnePlaneIsOutsideAndOneThatReachesIntoTheViewIsNot) {
  const glm::mat4 m = world_to_clip(looking_down_minus_z(), 1.0f);
  EXPECT_TRUE(raster::wholly_outside_view(box({3, -1, -1}, {4, 1, 1}), m));      // right
  EXPECT_TRUE(raster::wholly_outside_view(box({-4, -1, -1}, {-3, 1, 1}), m));    // left
  EXPECT_TRUE(raster::wholly_outside_view(box({-1, 3, -1}, {1, 4, 1}), m));      // above
  EXPECT_TRUE(raster::wholly_outside_view(box({-1, -4, -1}, {1, -3, 1}), m));    // below
  EXPECT_TRUE(raster::wholly_outside_view(box({-1, -1, 6}, {1, 1, 8}), m));      // behind the camera
  EXPECT_TRUE(raster::wholly_outside_view(box({-1, -1, -1e6f}, {1, 1, -9e5f}), m));  // past the far plane
  EXPECT_FALSE(raster::wholly_outside_view(box({-1, -1, -1}, {1, 1, 1}), m));    // in the middle
  EXPECT_FALSE(raster::wholly_outside_view(box({1.5f, -1, -1}, {4, 1, 1}), m));  // across the right edge
  EXPECT_FALSE(raster::wholly_outside_view(box({-1, -1, 4}, {1, 1, 6}), m));     // around the camera
  // Outside two planes' corners but not wholly beyond either: the corner of the view is in it.
  EXPECT_FALSE(raster::wholly_outside_view(box({1.5f, 1.5f, -1}, {4, 4, 1}), m));
  EXPECT_FALSE(raster::wholly_outside_view(AABB{}, m));  // empty
  EXPECT_FALSE(raster::wholly_outside_view(box({3, -1, -1}, {std::numeric_limits<float>::infinity(), 1, 1}), m));
}

// Boxes laid against the frustum's planes, a hair outside or inside or clearly beyond, carried by
// random transforms: whenever one is culled, every point of it the vertex stage carries to clip
// space (in float, as raster_frame.cpp does: the matrices' product, then the point) lies beyond
// one common plane. Without view_culling.cpp's margin this fails.
TEST(ViewCulling, EveryPointOfACulledBoxIsBeyondOnePlaneAfterTheFloatVertexStage) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), sym(-1.0f, 1.0f);
  const Camera camera = looking_down_minus_z();
  const glm::mat4 view_projection = world_to_clip(camera, 16.0f / 9.0f);
  int culled = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const glm::mat4 model_to_world =
        test::placed({sym(rng) * 3, sym(rng) * 3, sym(rng) * 3}, glm::normalize(glm::vec3(sym(rng), sym(rng), sym(rng)) + 1e-3f),
                     unit(rng) * 360.0f, glm::vec3(0.1f + unit(rng) * 3));
    const glm::mat4 to_clip = view_projection * model_to_world;
    // A small box, then slid so that one corner sits on a plane of the view, give or take a hair.
    const glm::vec3 lo(sym(rng), sym(rng), sym(rng)), size(0.05f + unit(rng), 0.05f + unit(rng), 0.05f + unit(rng));
    AABB b = box(lo, lo + size);
    const glm::vec4 corner = to_clip * glm::vec4(b.max, 1.0f);
    const int plane = trial % 4;
    const float ndc = plane % 2 ? -1.0f : 1.0f;
    const float coordinate = plane < 2 ? corner.x : corner.y;
    if (!(corner.w > 0.1f)) continue;
    // Half the boxes a few float steps from the plane, either side; half clearly beyond it.
    const float offset = trial % 8 < 4 ? (unit(rng) - 0.5f) * 4e-6f : unit(rng) * 5e-3f;
    const float shift_ndc = ndc - coordinate / corner.w + ndc * offset;
    glm::vec4 shift_clip(0.0f);
    (plane < 2 ? shift_clip.x : shift_clip.y) = shift_ndc * corner.w;
    const glm::vec3 shift_world = glm::vec3(glm::inverse(view_projection) * shift_clip);
    const glm::vec3 shift_model = glm::vec3(glm::inverse(model_to_world) * glm::vec4(shift_world, 0.0f));
    b = box(b.min + shift_model, b.max + shift_model);
    if (!raster::wholly_outside_view(b, to_clip)) continue;
    ++culled;
    // Which planes each point is beyond, in float: their intersection must not be empty.
    unsigned common = 0x3f;
    for (int s = 0; s < 64; ++s) {
      const glm::vec3 p = s < 8 ? glm::vec3(s & 1 ? b.max.x : b.min.x, s & 2 ? b.max.y : b.min.y, s & 4 ? b.max.z : b.min.z)
                                : glm::mix(b.min, b.max, glm::vec3(unit(rng), unit(rng), unit(rng)));
      const glm::vec4 c = to_clip * glm::vec4(p, 1.0f);
      unsigned beyond = 0;
      if (c.z + c.w < 0.0f) beyond |= 1;
      if (c.w - c.z < 0.0f) beyond |= 2;
      if (c.w - c.x < 0.0f) beyond |= 4;
      if (c.w + c.x < 0.0f) beyond |= 8;
      if (c.w - c.y < 0.0f) beyond |= 16;
      if (c.w + c.y < 0.0f) beyond |= 32;
      common &= beyond;
    }
    ASSERT_NE(common, 0u) << "trial " << trial << ": a culled box has a point inside every plane";
  }
  EXPECT_GT(culled, 200);  // the boxes near the planes were tried, not only far ones
}

// A frame of one visible grid and copies of it out of sight (beside the view, behind the camera,
// past the far plane) and across the view's edge: the copies out of sight are skipped, the one
// across the edge is drawn, and the image is the image of the scene without the skipped ones.
TEST(ViewCulling, AFramesMeshesOutOfSightAreSkippedAndItsImageKeepsEveryBit) {
  const auto scene_with = [](bool out_of_sight) {
    Scene scene;
    scene.camera = looking_down_minus_z();
    scene.objects.push_back(test::object_of(test::make_grid(8)));
    scene.objects.push_back(test::object_of(test::make_grid(8), glm::translate(glm::mat4(1.0f), {2.5f, 0.5f, 0.0f})));
    if (out_of_sight) {
      for (const glm::vec3& at : {glm::vec3(8, 0, 0), glm::vec3(-8, 0, 0), glm::vec3(0, 9, 0), glm::vec3(0, 0, 9),
                                  glm::vec3(0, 0, -5e5f)}) {
        scene.objects.push_back(test::object_of(test::make_grid(8), glm::translate(glm::mat4(1.0f), at)));
      }
    }
    scene.lights.push_back(Light{Light::Kind::Point, {1, 2, 4}, {}, glm::vec3(20.0f)});
    return PreparedScene(std::move(scene));
  };
  AovSet aovs;
  aovs.depth = true;
  aovs.normal = true;
  const RenderSettings settings = test::raster_settings(96, 64, aovs);
  const PreparedScene with = scene_with(true), without = scene_with(false);
  EXPECT_EQ(raster::build_raster_frame(with, settings, nullptr, CancelFlag::never())->meshes_outside_view, 5u);
  EXPECT_EQ(raster::build_raster_frame(without, settings, nullptr, CancelFlag::never())->meshes_outside_view, 0u);
  const TileBuffer a = test::render_full(with, settings), b = test::render_full(without, settings);
  EXPECT_EQ(test::differing_pixels(a, b), 0);
  int covered = 0;  // the grids in view were drawn, the second to the image's right edge
  for (int x = 0; x < 96; ++x) covered += a.depth(x, 32) < 1e30f ? 1 : 0;
  EXPECT_GT(covered, 40);
  EXPECT_LT(a.depth(95, 32), 1e30f);
}

}  // namespace
}  // namespace farm
