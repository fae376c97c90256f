// PreparedScene flattens its models for the ray engines only (renderer/accel/prepared_scene.h):
// counted, not timed.
#include "renderer/accel/prepared_scene.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

Scene two_models() {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_box({-0.5f, -0.5f, -0.5f}, {0.5f, 0.5f, 0.5f})));
  scene.objects.push_back(test::object_of(test::make_sphere(8, 16), test::placed({1.5f, 0, 0}, {0, 1, 0}, 0, {1, 1, 1})));
  scene.camera.position = {0.0f, 0.0f, 5.0f};
  return scene;
}

TEST(PreparedScene, ARasterFrameFlattensNoModelAndTheFirstRayQueryFlattensEachOnce) {
  const PreparedScene scene(two_models());
  const TileBuffer image = test::render_full(scene, test::raster_settings(48, 32));
  float lit = 0.0f;  // the frame was drawn: the box and the sphere cover pixels
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 48; ++x) lit += image.rgba(x, y).w;
  }
  EXPECT_GT(lit, 50.0f);
  EXPECT_EQ(scene.geometry().flattened_models(), 0u);
  for (const PreparedObject& object : scene.placements()) EXPECT_EQ(object.triangles, nullptr);

  // Ray engines' threads ask at once: every model is flattened once, and all see the same.
  std::vector<const ModelTriangles*> seen(8 * 2);
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      const std::vector<PreparedObject>& objects = scene.objects();
      for (std::size_t o = 0; o < objects.size(); ++o) seen[static_cast<std::size_t>(t) * 2 + o] = objects[o].triangles;
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(scene.geometry().flattened_models(), 2u);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    ASSERT_NE(seen[i], nullptr) << i;
    EXPECT_EQ(seen[i], seen[i % 2]) << i;
  }
  EXPECT_EQ(seen[0]->size(), 12u);  // the box's triangles
  EXPECT_EQ(scene.placements()[1].triangles, seen[1]);
}

}  // namespace
}  // namespace farm
