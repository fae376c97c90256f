// The rasterizer's frame set-up scales with threads (issue #32), held by counting, not timing:
// each of its stages (vertex stage, triangle set-up and binning, merge) is split across every
// thread of the pool, each thread's share is counted, the shares add up to the whole, and the
// threads write the state they share a bounded number of times per chunk, never per triangle
// (one shared write per triangle made two threads slower than one).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <set>

#include "renderer/raster/raster_frame.h"
#include "renderer/util/thread_pool.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

using Stage = raster::SetupObserver::Stage;

// Counts what each thread did, stage by stage. A stage's first chunk on a thread waits until a
// second thread has started a chunk of the same stage: a stage that is split across the pool
// meets there at once (no clock involved), however the threads happen to be scheduled; one run by
// a single thread waits in vain and is reported after `kGiveUp`, which only a broken split meets.
class CountingObserver final : public raster::SetupObserver {
 public:
  static constexpr auto kGiveUp = std::chrono::seconds(20);

  void chunk(Stage stage, int worker, std::size_t items) override {
    std::unique_lock lock(mutex_);
    Counts& c = counts_[stage];
    c.items[worker] += items;
    ++c.chunks[worker];
    if (c.threads.insert(worker).second) {
      met_.notify_all();
      if (!met_.wait_for(lock, kGiveUp, [&] { return c.threads.size() >= 2; })) c.met_alone = true;
    }
  }
  void shared_write() override {
    std::lock_guard lock(mutex_);
    ++shared_writes_;
  }

  struct Counts {
    std::map<int, std::size_t> items, chunks;  // by pool thread
    std::set<int> threads;
    bool met_alone = false;
    std::size_t total_items() const {
      std::size_t n = 0;
      for (const auto& [worker, count] : items) n += count;
      return n;
    }
    std::size_t total_chunks() const {
      std::size_t n = 0;
      for (const auto& [worker, count] : chunks) n += count;
      return n;
    }
  };
  Counts counts(Stage stage) const {
    std::lock_guard lock(mutex_);
    const auto it = counts_.find(stage);
    return it == counts_.end() ? Counts{} : it->second;
  }
  std::size_t shared_writes() const {
    std::lock_guard lock(mutex_);
    return shared_writes_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable met_;
  std::map<Stage, Counts> counts_;
  std::size_t shared_writes_ = 0;
};

// 320,000 triangles filling the view: dozens of chunks for every stage.
PreparedScene grid_filling_the_view() {
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_grid(400)));
  scene.camera.position = {0, 0, 2.5f};
  scene.camera.target = {0, 0, 0};
  return PreparedScene(std::move(scene));
}

TEST(RasterSetupSplit, EveryStageIsSplitAcrossThePoolsThreadsAndTheSharesAddUp) {
  const PreparedScene scene = grid_filling_the_view();
  const RenderSettings settings = test::raster_settings(1920, 1080);
  constexpr int kThreads = 2;
  ThreadPool pool(kThreads);
  CountingObserver observer;
  const auto frame = raster::build_raster_frame(scene, settings, &pool, CancelFlag::never(), &observer);

  const std::size_t vertices = 401 * 401, triangles = 400 * 400 * 2;
  const std::array<std::pair<Stage, std::size_t>, 3> stages{
      {{Stage::vertices, vertices}, {Stage::triangles, triangles}, {Stage::merge, frame->setup_chunks}}};
  for (const auto& [stage, whole] : stages) {
    SCOPED_TRACE("stage " + std::to_string(static_cast<int>(stage)));
    const CountingObserver::Counts c = observer.counts(stage);
    EXPECT_FALSE(c.met_alone) << "one thread ran the stage alone";
    EXPECT_EQ(c.items.size(), static_cast<std::size_t>(kThreads)) << "not every thread took part";
    for (const auto& [worker, items] : c.items) {
      EXPECT_GE(worker, 0);
      EXPECT_LT(worker, kThreads);
      EXPECT_GT(items, 0u) << "thread " << worker;
    }
    EXPECT_EQ(c.total_items(), whole) << "the shares do not add up to the stage's work";
  }
  // The set-up's shared bin-entry count is written once or twice per chunk of 8192 triangles
  // (it reports every 65,536 entries and at the chunk's end), not once per triangle.
  const std::size_t set_up_chunks = observer.counts(Stage::triangles).total_chunks();
  EXPECT_GE(set_up_chunks, 20u);
  EXPECT_LE(observer.shared_writes(), 2 * set_up_chunks) << "the set-up's threads write shared state per triangle";
  EXPECT_GE(frame->bin_start.back(), triangles / 2) << "the grid was not binned";
}

// The same frame built on one thread and on the pool is the same frame: the split changes who
// does the work, not what it makes.
TEST(RasterSetupSplit, ThePoolsFrameBinsTheSameTrianglesInTheSameOrderAsOneThreads) {
  const PreparedScene scene = grid_filling_the_view();
  const RenderSettings settings = test::raster_settings(640, 360);
  ThreadPool pool(2);
  const auto alone = raster::build_raster_frame(scene, settings, nullptr, CancelFlag::never());
  const auto split = raster::build_raster_frame(scene, settings, &pool, CancelFlag::never());
  ASSERT_EQ(alone->bin_start, split->bin_start);
  for (std::size_t i = 0; i < alone->bin_start.back(); ++i) {
    const raster::ScreenTriangle &a = alone->triangle(alone->bin_triangles[i]),
                                 &b = split->triangle(split->bin_triangles[i]);
    ASSERT_EQ(a.material, b.material) << i;
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(alone->vertex(a.v[k]).position.x, split->vertex(b.v[k]).position.x) << i;
      ASSERT_EQ(alone->vertex(a.v[k]).position.y, split->vertex(b.v[k]).position.y) << i;
    }
  }
}

}  // namespace
}  // namespace farm
