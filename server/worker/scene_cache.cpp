#include "server/worker/scene_cache.h"

#include <chrono>

namespace farm {

namespace {
// Mesh (positions, normals, indices), flattened triangles and a BVH per model, per triangle.
constexpr std::uint64_t kApproxBytesPerTriangle = 256;
// A frame that shares its models with another: world-space boxes and the rasterizer's set-up.
constexpr std::uint64_t kApproxFrameBytesPerTriangle = 64;
constexpr auto kLoadPollInterval = std::chrono::milliseconds(20);
}  // namespace

CachedScene::CachedScene(Job j, Scene s, std::shared_ptr<ModelLibrary> m, std::shared_ptr<ModelGeometry> geometry)
    : job(std::move(j)),
      models(m ? std::move(m) : std::make_shared<ModelLibrary>(job.asset_root)),
      prepared(std::move(s), geometry) {
  approx_bytes = (geometry ? kApproxFrameBytesPerTriangle : kApproxBytesPerTriangle) * prepared.triangle_count() +
                 sizeof(CachedScene);
}

SceneCache::Lookup SceneCache::get(const std::string& scene_hash, const Prepare& prepare,
                                   const Cancelled& cancelled) {
  std::promise<std::shared_ptr<const CachedScene>> promise;
  std::shared_future<std::shared_ptr<const CachedScene>> future;
  {
    std::lock_guard lock(mutex_);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->hash == scene_hash) {
        entries_.splice(entries_.begin(), entries_, it);
        future = it->future;
        break;
      }
    }
    if (!future.valid()) entries_.push_front({scene_hash, promise.get_future().share(), 0, false});
  }

  if (future.valid()) {
    while (future.wait_for(kLoadPollInterval) != std::future_status::ready) {
      if (cancelled && cancelled()) return {nullptr, true};
    }
    return {future.get(), true};
  }

  std::shared_ptr<const CachedScene> scene;
  try {
    scene = prepare();
  } catch (...) {
    forget(scene_hash);
    promise.set_exception(std::current_exception());
    throw;
  }
  promise.set_value(scene);
  finish(scene_hash, scene);
  return {scene, false};
}

void SceneCache::finish(const std::string& hash, const std::shared_ptr<const CachedScene>& scene) {
  std::lock_guard lock(mutex_);
  std::size_t ready = 0;
  std::uint64_t total = 0;
  for (Entry& e : entries_) {
    if (e.hash == hash) {
      e.ready = true;
      e.bytes = scene->approx_bytes;
    }
    if (e.ready) {
      ++ready;
      total += e.bytes;
    }
  }
  // Evict from the least recently used end, never the scene just prepared (a single scene over
  // the budget still has to render) and never one still being prepared. Requests holding an
  // evicted scene keep it alive until they finish.
  for (auto it = entries_.end(); it != entries_.begin() && (ready > limits_.max_scenes ||
                                                           total > limits_.max_bytes);) {
    --it;
    if (!it->ready || it->hash == hash) continue;
    --ready;
    total -= it->bytes;
    it = entries_.erase(it);
  }
}

void SceneCache::forget(const std::string& hash) {
  std::lock_guard lock(mutex_);
  entries_.remove_if([&](const Entry& e) { return e.hash == hash; });
}

std::size_t SceneCache::size() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const Entry& e : entries_) n += e.ready ? 1 : 0;
  return n;
}

std::uint64_t SceneCache::bytes() const {
  std::lock_guard lock(mutex_);
  std::uint64_t n = 0;
  for (const Entry& e : entries_) n += e.bytes;
  return n;
}

}  // namespace farm
