#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>
#include <vector>

#include "server/worker/scene_cache.h"

namespace farm {
namespace {

std::shared_ptr<const CachedScene> empty_scene() {
  return std::make_shared<const CachedScene>(Job{}, Scene{});
}

TEST(SceneCache, ConcurrentRequestsForOneScenePrepareItOnce) {
  SceneCache cache({4, 1u << 30});
  std::atomic<int> prepared{0};
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  const auto prepare = [&] {
    ++prepared;
    released.wait();  // hold the preparation until every request has arrived
    return empty_scene();
  };
  std::vector<std::future<SceneCache::Lookup>> lookups;
  for (int i = 0; i < 6; ++i) {
    lookups.push_back(std::async(std::launch::async, [&] { return cache.get("s", prepare, {}); }));
  }
  // The first request is preparing; give the others a bounded time to join it.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (prepared == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  release.set_value();
  std::shared_ptr<const CachedScene> first;
  for (auto& f : lookups) {
    const SceneCache::Lookup l = f.get();
    ASSERT_TRUE(l.scene);
    if (!first) first = l.scene;
    EXPECT_EQ(l.scene, first);
  }
  EXPECT_EQ(prepared, 1);
  EXPECT_EQ(cache.size(), 1u);
}

TEST(SceneCache, LeastRecentlyUsedSceneIsEvictedBeyondTheCount) {
  SceneCache cache({2, 1u << 30});
  int prepared = 0;
  const auto prepare = [&] {
    ++prepared;
    return empty_scene();
  };
  cache.get("a", prepare, {});
  cache.get("b", prepare, {});
  cache.get("a", prepare, {});  // a is now the most recently used
  cache.get("c", prepare, {});  // evicts b
  EXPECT_EQ(prepared, 3);
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_TRUE(cache.get("a", prepare, {}).hit);
  EXPECT_FALSE(cache.get("b", prepare, {}).hit);
  EXPECT_EQ(prepared, 4);
}

TEST(SceneCache, MemoryBudgetBoundsTheCacheButKeepsTheNewestScene) {
  const std::uint64_t one = empty_scene()->approx_bytes;
  SceneCache cache({100, one + one / 2});
  const auto prepare = [] { return empty_scene(); };
  cache.get("a", prepare, {});
  cache.get("b", prepare, {});
  EXPECT_EQ(cache.size(), 1u);
  EXPECT_TRUE(cache.get("b", prepare, {}).hit);
  EXPECT_LE(cache.bytes(), one + one / 2);
}

TEST(SceneCache, FailedPreparationIsRethrownAndNotCached) {
  SceneCache cache({4, 1u << 30});
  EXPECT_THROW(cache.get("s", [] () -> std::shared_ptr<const CachedScene> {
    throw std::runtime_error("broken");
  }, {}), std::runtime_error);
  EXPECT_EQ(cache.size(), 0u);
  EXPECT_FALSE(cache.get("s", [] { return empty_scene(); }, {}).hit);
}

}  // namespace
}  // namespace farm
