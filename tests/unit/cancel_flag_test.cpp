// The cancellation token (renderer/util/cancel_flag.h) and every engine's use of it: a render with
// a billion samples per pixel stops at a cancel or a deadline after a bounded amount of work,
// leaves no pixels behind, and a flag that never stops it changes no bit. Work is counted with the
// engines' own counters and the flag's poll countdown, never with a stopwatch.
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <ostream>
#include <string>
#include <thread>

#include "renderer/engine.h"
#include "renderer/util/cancel_flag.h"
#include "tests/support/print_values.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

using namespace std::chrono_literals;
using Clock = CancelFlag::Clock;

// Days of work for a 16x16 tile: only a stop ends such a render.
constexpr int kHugeSpp = 1'000'000'000;
// Seconds of work for a 16x16 tile: enough to tell a render that stopped from one that ran to the
// end, and an engine that ignores its flag fails the test instead of hanging it.
constexpr int kLargeSpp = 1 << 16;

TEST(CancelFlag, WithoutADeadlineStopsOnlyWhenCancelled) {
  CancelFlag flag;
  EXPECT_EQ(flag.deadline(), Clock::time_point::max());
  for (int i = 0; i < 1000; ++i) ASSERT_FALSE(flag.stop_requested());
  EXPECT_EQ(flag.reason(), StopReason::None);
  flag.cancel();
  EXPECT_TRUE(flag.stop_requested());
  EXPECT_EQ(flag.reason(), StopReason::Cancelled);
  EXPECT_TRUE(flag.stop_requested()) << "a stopped flag stays stopped";
}

TEST(CancelFlag, PassedDeadlineStopsWithReasonDeadlineAndKeepsIt) {
  CancelFlag flag(Clock::now() - 1ms);
  EXPECT_EQ(flag.reason(), StopReason::None) << "nothing has polled it yet";
  EXPECT_TRUE(flag.stop_requested());
  EXPECT_EQ(flag.reason(), StopReason::Deadline);
  flag.cancel();  // the first reason wins
  EXPECT_EQ(flag.reason(), StopReason::Deadline);
}

TEST(CancelFlag, CancelledBeforeTheDeadlineSaysCancelled) {
  CancelFlag flag(Clock::now() + 1h);
  EXPECT_FALSE(flag.stop_requested());
  flag.cancel();
  EXPECT_TRUE(flag.stop_requested());
  EXPECT_EQ(flag.reason(), StopReason::Cancelled);
}

TEST(CancelFlag, CancelFromAnotherThreadIsSeen) {
  CancelFlag flag;
  std::thread canceller([&] { flag.cancel(); });
  canceller.join();
  EXPECT_TRUE(flag.stop_requested());
}

TEST(CancelFlag, SteadyDeadlineOfAWallClockOne) {
  using System = std::chrono::system_clock;
  EXPECT_EQ(CancelFlag::steady_deadline(System::time_point::max()), Clock::time_point::max());
  const Clock::time_point past = CancelFlag::steady_deadline(System::now() - 1h);
  EXPECT_LE(past, Clock::now());
  const Clock::time_point in_an_hour = CancelFlag::steady_deadline(System::now() + 1h);
  EXPECT_GT(in_an_hour, Clock::now() + 59min);
  EXPECT_LT(in_an_hour, Clock::now() + 61min);
  EXPECT_FALSE(CancelFlag::never().stop_requested());
}

TEST(CancelFlag, CancelAtPollTripsAtThatPoll) {
  CancelFlag flag;
  flag.cancel_at_poll(3);
  EXPECT_FALSE(flag.stop_requested());
  EXPECT_FALSE(flag.stop_requested());
  EXPECT_TRUE(flag.stop_requested());
  EXPECT_EQ(flag.reason(), StopReason::Cancelled);
}

TEST(CancelPoll, LooksAtTheFirstUnitThenOnceEveryNUnitsAndStaysStopped) {
  CancelFlag flag;
  flag.cancel_at_poll(3);  // the third look says stop
  CancelPoll poll(flag, 4);
  int units = 0;
  while (!poll()) ++units;
  // Looks at units 1, 5 and 9: eight units went by before the third look stopped them.
  EXPECT_EQ(units, 8);
  EXPECT_TRUE(poll.stopped());
  EXPECT_TRUE(poll()) << "once stopped, every later call says so";

  CancelFlag stopped;
  stopped.cancel();
  CancelPoll first(stopped, 1000);
  EXPECT_TRUE(first()) << "the first unit looks, so a stopped flag stops all work";
}

// A lit box in front of the camera, for every engine.
PreparedScene lit_box() {
  Scene scene;
  Material m;
  m.diffuse = glm::vec3(0.7f);
  scene.objects.push_back(test::object_of(test::make_box({-1, -1, -1}, {1, 1, 1}), glm::mat4(1.0f), m));
  Light light;
  light.position = {3, 4, 5};
  light.intensity = glm::vec3(20.0f);
  scene.lights.push_back(light);
  return PreparedScene(std::move(scene));
}

RenderSettings settings_for(EngineKind engine, int size, int spp) {
  RenderSettings s = test::raster_settings(size, size);
  s.engine = engine;
  s.spp = spp;
  s.max_depth = 5;
  return s;
}

// Work an engine counts as it goes: path samples, closest-hit and shadow rays, fragments.
std::uint64_t work_done(const RenderStats& s) { return s.samples + s.rays + s.fragments; }

bool same_bits(const TileBuffer& a, const TileBuffer& b) {
  if (!(a.rect() == b.rect())) return false;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      if (std::memcmp(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) != 0) return false;
      const float da = a.aovs().depth ? a.depth(x, y) : 0.0f, db = b.aovs().depth ? b.depth(x, y) : 0.0f;
      if (std::memcmp(&da, &db, sizeof(float)) != 0) return false;
      if (a.aovs().normal && std::memcmp(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3)) != 0) return false;
    }
  }
  return true;
}

class EngineCancel : public ::testing::TestWithParam<EngineKind> {
 protected:
  PreparedScene scene_ = lit_box();
};

TEST_P(EngineCancel, AStoppedFlagStopsTheRenderBeforeAnyWork) {
  const RenderSettings settings = settings_for(GetParam(), 16, kLargeSpp);
  CancelFlag flag;
  flag.cancel();
  TileBuffer out;
  EXPECT_EQ(render_tile(scene_, settings, {0, 0, 16, 16}, out, flag), StopReason::Cancelled);
  EXPECT_TRUE(out.rect().empty()) << "a stopped render leaves no pixels";
  EXPECT_EQ(work_done(out.stats()), 0u);
}

// A cancel that arrives mid-tile, at the flag's 50th poll: the tile is 256 pixels x 65536 samples
// of work, and the render stops after a few thousand units of it, the pixels dropped.
TEST_P(EngineCancel, CancelledMidTileStopsAfterABoundedAmountOfWork) {
  const RenderSettings settings = settings_for(GetParam(), 16, kLargeSpp);
  CancelFlag flag;
  flag.cancel_at_poll(50);
  TileBuffer out;
  EXPECT_EQ(render_tile(scene_, settings, {0, 0, 16, 16}, out, flag), StopReason::Cancelled);
  EXPECT_TRUE(out.rect().empty());
  const std::uint64_t work = work_done(out.stats());
  EXPECT_GT(work, 0u) << "the render had started";
  // At most 64 rays (whitted), 32 path segments or 256 triangles or one bin pass (raster) go by
  // between polls: 50 polls bound the work to thousands of rays or fragments.
  const std::uint64_t bound = GetParam() == EngineKind::Raster ? 50u * 16 * 16 : 50u * 64 * 4;
  EXPECT_LE(work, bound);
}

// A deadline needs no one watching: the engine polls it. The render would otherwise run for days;
// that it returns at all, with Deadline and no pixels, is what this checks.
TEST_P(EngineCancel, DeadlineStopsAHugeRenderByItself) {
  const RenderSettings settings = settings_for(GetParam(), 16, kHugeSpp);
  const CancelFlag flag(Clock::now() + 200ms);
  TileBuffer out;
  EXPECT_EQ(render_tile(scene_, settings, {0, 0, 16, 16}, out, flag), StopReason::Deadline);
  EXPECT_TRUE(out.rect().empty());
  EXPECT_GT(work_done(out.stats()), 0u);
}

TEST_P(EngineCancel, AFlagThatNeverStopsChangesNoBit) {
  RenderSettings settings = settings_for(GetParam(), 24, 4);
  settings.aovs.depth = true;
  settings.aovs.normal = true;
  TileBuffer plain, with_flag;
  render_tile(scene_, settings, {3, 2, 21, 23}, plain);
  const CancelFlag flag(Clock::now() + 1h);
  EXPECT_EQ(render_tile(scene_, settings, {3, 2, 21, 23}, with_flag, flag), StopReason::None);
  EXPECT_TRUE(same_bits(plain, with_flag));
  EXPECT_GT(plain.rgba(12, 12).x, 0.0f) << "the box is lit there";
}

INSTANTIATE_TEST_SUITE_P(AllEngines, EngineCancel,
                         ::testing::Values(EngineKind::Raster, EngineKind::Whitted, EngineKind::Path),
                         [](const ::testing::TestParamInfo<EngineKind>& engine) {
                           return std::string(to_string(engine.param));
                         });

}  // namespace
}  // namespace farm
