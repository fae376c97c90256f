#pragma once
// Prepared scenes by scene hash, least recently used first out, bounded by a count and by an
// approximate memory budget. Concurrent requests for a scene not yet cached prepare it once: the
// first runs the preparation, the others wait for its result (or its error).
#include <cstdint>
#include <functional>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <string>

#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/loaders/model_library.h"

namespace farm {

// One frame of a job, prepared. The frames of a job share its loaded models and their BVHs:
// the first frame prepared (the job's own entry, by its scene hash) makes `models` and
// `geometry`, and every other frame's entry is built from them.
struct CachedScene {
  // `models` null: a library of its own (the scene's models were loaded elsewhere, and the
  // job's other frames load them once more, into it).
  // `geometry` given: another frame's, whose models this frame shares (and is counted smaller).
  CachedScene(Job j, Scene s, std::shared_ptr<ModelLibrary> models = nullptr,
              std::shared_ptr<ModelGeometry> geometry = nullptr);

  Job job;  // at its frame
  std::shared_ptr<ModelLibrary> models;
  PreparedScene prepared;
  // An estimate, not a measurement: meshes, flattened triangles and the BVHs engines build
  // lazily all grow with the triangle count.
  std::uint64_t approx_bytes = 0;
};

struct SceneCacheLimits {
  std::size_t max_scenes = 8;
  std::uint64_t max_bytes = std::uint64_t{4} << 30;
};

class SceneCache {
 public:
  explicit SceneCache(SceneCacheLimits limits) : limits_(limits) {}

  using Prepare = std::function<std::shared_ptr<const CachedScene>()>;
  // Polled while waiting for another request's preparation; true = stop waiting.
  using Cancelled = std::function<bool()>;

  struct Lookup {
    std::shared_ptr<const CachedScene> scene;  // null when `cancelled` ended the wait
    bool hit = false;                          // ready (or being prepared) before this call
  };

  // The cached scene, or prepare() run once on this thread. Rethrows prepare's exception (to
  // every waiter); a failed preparation is not cached, so a later request tries again.
  Lookup get(const std::string& scene_hash, const Prepare& prepare, const Cancelled& cancelled);

  std::size_t size() const;
  std::uint64_t bytes() const;

 private:
  struct Entry {
    std::string hash;
    std::shared_future<std::shared_ptr<const CachedScene>> future;
    std::uint64_t bytes = 0;  // 0 while being prepared
    bool ready = false;
  };

  void finish(const std::string& hash, const std::shared_ptr<const CachedScene>& scene);
  void forget(const std::string& hash);

  SceneCacheLimits limits_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  // most recently used first
};

}  // namespace farm
