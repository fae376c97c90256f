// A frame's set-up stops at a cancel too, not only its tiles: the BVH builds (ours and Embree's)
// and the rasterizer's vertex stage, set-up and binning poll the CancelFlag and throw
// RenderStopped, the frame cache neither keeps a stopped build nor lets a waiter's cancel wait on
// another's build, and a tile whose set-up was stopped returns the StopReason without pixels.
// Stops come from the flag's poll countdown (cancel_at_poll), never from a stopwatch.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "renderer/accel/scene_intersector.h"
#include "renderer/engine.h"
#include "renderer/geometry/bvh.h"
#include "renderer/raster/raster_frame.h"
#include "renderer/util/cancel_flag.h"
#include "renderer/util/frame_cache.h"
#include "renderer/util/input_error.h"
#include "tests/support/print_values.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

std::vector<AABB> random_boxes(std::size_t count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> at(-100.0f, 100.0f);
  std::vector<AABB> boxes(count);
  for (AABB& box : boxes) {
    const glm::vec3 p(at(rng), at(rng), at(rng));
    box = AABB{};
    box.grow(p);
    box.grow(p + glm::vec3(0.5f));
  }
  return boxes;
}

TEST(SetupCancel, ABvhBuildStopsPartWayAtACancel) {
  const std::vector<AABB> boxes = random_boxes(400'000);
  CancelFlag flag;
  flag.cancel_at_poll(3);  // the root's split looks once, its two children twice more
  try {
    Bvh::build(boxes, Bvh::Options{BvhSplit::Sah, 4, &flag});
    FAIL() << "the build ran to the end through a cancel";
  } catch (const RenderStopped& stopped) {
    EXPECT_EQ(stopped.reason(), StopReason::Cancelled);
  }
  // The same build without a flag, and with one that never stops, is whole.
  const Bvh whole = Bvh::build(boxes, Bvh::Options{BvhSplit::Sah, 4});
  const Bvh never = Bvh::build(boxes, Bvh::Options{BvhSplit::Sah, 4, &CancelFlag::never()});
  EXPECT_EQ(whole.nodes().size(), never.nodes().size());
  EXPECT_GT(whole.nodes().size(), 1000u);
}

// A scene of one large grid (320,000 triangles), for builds that take long enough to poll.
PreparedScene big_grid_scene() {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_grid(400)));
  return PreparedScene(std::move(scene));
}

class IntersectorSetupCancel : public ::testing::TestWithParam<AccelKind> {};

// Embree's build polls through its progress callback: a stop at the flag's second poll can only
// come from the callback, since the check after the build polls once.
TEST_P(IntersectorSetupCancel, TheBuildStopsAtItsSecondPoll) {
  const PreparedScene scene = big_grid_scene();
  CancelFlag flag;
  flag.cancel_at_poll(2);
  try {
    build_scene_intersector(scene, GetParam(), flag);
    FAIL() << to_string(GetParam()) << ": the build ran to the end through a cancel";
  } catch (const RenderStopped& stopped) {
    EXPECT_EQ(stopped.reason(), StopReason::Cancelled);
  }
}

TEST_P(IntersectorSetupCancel, ACancelledBuildIsNotCachedAndTheNextRequestBuildsIt) {
  const PreparedScene scene = big_grid_scene();
  CancelFlag stopped;
  stopped.cancel();
  EXPECT_THROW(cached_scene_intersector(scene, GetParam(), stopped), RenderStopped);
  const auto built = cached_scene_intersector(scene, GetParam());
  ASSERT_TRUE(built);
  SurfaceHit hit;
  EXPECT_TRUE(built->closest_hit(Ray{{0.1f, 0.2f, 5.0f}, {0, 0, -1}}, hit)) << "a whole intersector";
}

INSTANTIATE_TEST_SUITE_P(Accels, IntersectorSetupCancel,
                         ::testing::Values(AccelKind::Bvh, AccelKind::BvhMedian, AccelKind::Embree),
                         [](const ::testing::TestParamInfo<AccelKind>& accel) {
                           std::string name(to_string(accel.param));
                           std::erase(name, '-');
                           return name;
                         });

// Quads facing the camera that each cover the whole image: the most bin entries per triangle.
PreparedScene screen_covering_quads(int count) {
  Scene scene;
  for (int i = 0; i < count; ++i) {
    const float z = -0.001f * static_cast<float>(i);
    scene.objects.push_back(test::object_of(
        test::make_quad({-50, -50, z}, {50, -50, z}, {50, 50, z}, {-50, 50, z})));
  }
  scene.camera.position = {0, 0, 5};
  scene.camera.target = {0, 0, 0};
  return PreparedScene(std::move(scene));
}

TEST(SetupCancel, TheRasterSetUpStopsAtACancel) {
  const PreparedScene scene = screen_covering_quads(64);
  RenderSettings settings = test::raster_settings(4096, 4096);
  settings.spp = 4;
  CancelFlag flag;
  flag.cancel_at_poll(4);
  EXPECT_THROW(raster::build_raster_frame(scene, settings, nullptr, flag), RenderStopped);
  EXPECT_NO_THROW(raster::build_raster_frame(scene, settings, nullptr, CancelFlag::never()));
}

// Few triangles that each fill every bin of a large image: the binning itself polls (by the bin
// entries it files), or one look would stand for seconds of work. Eight quads at 8192x8192 file
// about a million entries: a hundred looks or more, where counting triangles would look thrice.
TEST(SetupCancel, BinningLargeTrianglesPollsByTheEntriesItFiles) {
  const PreparedScene scene = screen_covering_quads(8);
  RenderSettings settings = test::raster_settings(8192, 8192);
  CancelFlag flag;
  flag.cancel_at_poll(100);
  EXPECT_THROW(raster::build_raster_frame(scene, settings, nullptr, flag), RenderStopped);
}

// Asks for a stop at the flag's `look`th look from the start of the set-up's merge on.
class StopInTheMerge final : public raster::SetupObserver {
 public:
  StopInTheMerge(CancelFlag& flag, std::int64_t look) : flag_(flag), look_(look) {}
  void chunk(Stage stage, int, std::size_t) override {
    if (stage == Stage::merge) flag_.cancel_at_poll(look_);
  }
  void shared_write() override {}

 private:
  CancelFlag& flag_;
  std::int64_t look_;
};

// The merge files the entries the set-up counted, and polls by them too: the same million entries
// in one set-up chunk give it a hundred looks or more, so a stop at its 50th stops the frame,
// where one look per chunk would let it run to the end.
TEST(SetupCancel, TheMergePollsByTheEntriesItFiles) {
  const PreparedScene scene = screen_covering_quads(8);
  RenderSettings settings = test::raster_settings(8192, 8192);
  CancelFlag flag;
  StopInTheMerge observer(flag, 50);
  EXPECT_THROW(raster::build_raster_frame(scene, settings, nullptr, flag, &observer), RenderStopped);
  CancelFlag fresh;
  StopInTheMerge never_reached(fresh, 100'000);  // past the merge's last look: the frame is whole
  EXPECT_NO_THROW(raster::build_raster_frame(scene, settings, nullptr, fresh, &never_reached));
}

// 2^26 bin entries at most: 300 quads (600 triangles) over a 16384x16384 image would file each
// triangle in all 262,144 bins, 157 million entries.
TEST(SetupCancel, AFrameOfTooManyBinEntriesIsRefusedSayingWhy) {
  const PreparedScene scene = screen_covering_quads(300);
  RenderSettings settings = test::raster_settings(16384, 16384);
  try {
    raster::build_raster_frame(scene, settings, nullptr, CancelFlag::never());
    FAIL() << "the frame was built";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than 67108864 triangle-in-bin entries"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("16384x16384"), std::string::npos) << e.what();
  }
  // A tenth of them is an honest frame.
  const PreparedScene fewer = screen_covering_quads(30);
  EXPECT_NO_THROW(raster::build_raster_frame(fewer, settings, nullptr, CancelFlag::never()));
}

class TileSetupCancel : public ::testing::TestWithParam<EngineKind> {};

// render_tile builds the frame's set-up itself when prepare_frame did not: a cancel there comes
// back as the tile's StopReason, with no pixels, and the set-up is built whole by the next tile.
TEST_P(TileSetupCancel, ACancelDuringTheSetUpIsTheTilesStopReason) {
  const PreparedScene scene = GetParam() == EngineKind::Raster ? screen_covering_quads(64) : big_grid_scene();
  RenderSettings settings = test::raster_settings(64, 64);
  settings.engine = GetParam();
  settings.spp = 1;
  CancelFlag flag;
  flag.cancel_at_poll(2);
  TileBuffer out;
  EXPECT_EQ(render_tile(scene, settings, {0, 0, 16, 16}, out, flag), StopReason::Cancelled);
  EXPECT_TRUE(out.rect().empty()) << "a stopped tile leaves no pixels";
  TileBuffer again;
  render_tile(scene, settings, {0, 0, 16, 16}, again);
  EXPECT_EQ(again.rect().width(), 16);
}

INSTANTIATE_TEST_SUITE_P(AllEngines, TileSetupCancel,
                         ::testing::Values(EngineKind::Raster, EngineKind::Whitted, EngineKind::Path),
                         [](const ::testing::TestParamInfo<EngineKind>& engine) {
                           return std::string(to_string(engine.param));
                         });

// One thread builds; another asks for the same key and cancels its wait: it stops waiting while
// the build goes on, and the build's value is cached for everyone else.
TEST(FrameCacheCancel, AWaiterStopsWaitingAtItsCancelWhileTheBuildGoesOn) {
  FrameCache cache;
  std::atomic<bool> building{false}, release{false};
  std::thread builder([&] {
    cache.get_or_build<int>("frame", CancelFlag::never(), [&] {
      building = true;
      while (!release) std::this_thread::yield();
      return std::make_shared<const int>(42);
    });
  });
  while (!building) std::this_thread::yield();
  CancelFlag flag;
  flag.cancel_at_poll(3);  // the waiter's third look at its flag
  EXPECT_THROW(cache.get_or_build<int>("frame", flag, [] { return std::make_shared<const int>(0); }),
               RenderStopped);
  release = true;
  builder.join();
  int builds = 0;
  const auto value = cache.get_or_build<int>("frame", CancelFlag::never(), [&] {
    ++builds;
    return std::make_shared<const int>(0);
  });
  EXPECT_EQ(*value, 42);
  EXPECT_EQ(builds, 0) << "the first build was kept";
}

// The builder's own caller cancels: a waiter whose flag has not stopped builds the value itself
// rather than inheriting the other caller's stop.
TEST(FrameCacheCancel, AWaiterBuildsItselfWhenTheBuildersCallerCancelled) {
  FrameCache cache;
  std::atomic<bool> building{false}, stop{false};
  std::thread builder([&] {
    EXPECT_THROW(cache.get_or_build<int>("frame", CancelFlag::never(),
                                         [&]() -> std::shared_ptr<const int> {
                                           building = true;
                                           while (!stop) std::this_thread::yield();
                                           throw RenderStopped(StopReason::Cancelled);
                                         }),
                 RenderStopped);
  });
  while (!building) std::this_thread::yield();
  // The builder gives up a moment after this thread has begun to wait (were it earlier, this
  // thread would build without waiting: the test would prove less, never fail).
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
  });
  const auto value = cache.get_or_build<int>("frame", CancelFlag::never(), [] { return std::make_shared<const int>(7); });
  canceller.join();
  builder.join();
  EXPECT_EQ(*value, 7);
}

}  // namespace
}  // namespace farm
