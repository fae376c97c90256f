#pragma once
// The body of farm.v1.Worker.RenderTile as a reusable object: a job spec and a rectangle in, the
// rectangle's pixels out, through the worker's asset store, scene cache and render threads. The
// gRPC WorkerService and the scheduler's in-process worker (embedded mode) both call this, so a
// tile is rendered by one piece of code whichever way it travels.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/util/thread_pool.h"
#include "server/common/asset_store.h"
#include "server/common/client_identity.h"
#include "server/common/log.h"
#include "server/worker/asset_fetcher.h"
#include "server/worker/scene_cache.h"

#include <grpcpp/support/status.h>

#include <string>
#include <vector>

namespace farm {

struct TileRendererOptions {
  std::filesystem::path blobs_dir;    // content-addressed assets (AssetStore)
  std::filesystem::path cache_dir;    // scenes/<scene hash>/ are laid out here
  // host:port of the schedulers to fetch missing assets from (asset_fetcher.h); none: none.
  std::vector<std::string> schedulers;
  ClientIdentity scheduler_identity;  // the worker's token and TLS for the schedulers
  int threads = 0;                    // render threads; 0 = all hardware threads
  std::size_t max_scenes = 8;
  std::uint64_t cache_memory_mb = 4096;
  // The "worker" log on stderr unless the operator chose (set_log_level): scenes prepared at
  // info, failed calls at warn, every call at debug.
  LogLevel log_level = LogLevel::info;
};

// How a caller stops a render. `cancelled` is polled every few milliseconds while the call
// waits, and a stop is passed on to the render threads through the call's CancelFlag
// (renderer/util/cancel_flag.h), which they poll every few samples, with the deadline in it.
struct RenderControl {
  std::function<bool()> cancelled;                        // true = stop (CANCELLED)
  std::chrono::system_clock::time_point deadline =        // passed = stop (DEADLINE_EXCEEDED)
      std::chrono::system_clock::time_point::max();
};

class TileRenderer {
 public:
  explicit TileRenderer(const TileRendererOptions& options);

  // Never throws: every failure is a status (INVALID_ARGUMENT for a bad job or rect,
  // FAILED_PRECONDITION for missing assets, CANCELLED / DEADLINE_EXCEEDED when stopped).
  grpc::Status render(const v1::RenderTileRequest& request, v1::RenderTileResponse& response,
                      const RenderControl& control);
  // The same, the pixels left as rendered instead of encoded (a caller in this process). Given a
  // `film` (the frame's, in this process) that covers the rect with the render's AOVs, the
  // sub-tiles are pasted straight into it instead, and an OK call leaves `pixels` empty (no
  // rect): no buffer of the call's own, no copy at the merge. Into a film, a call returns only
  // once none of its render threads can write to it any more, stopped or not.
  grpc::Status render(const v1::RenderTileRequest& request, TileBuffer& pixels,
                      v1::TileStats& stats, const RenderControl& control, TileBuffer* film = nullptr);

  // Caches a scene built elsewhere in this process from `job` (its models loaded by `models`) as
  // if a call had prepared it, and returns the cached one (the earlier one when the hash was
  // cached already).
  std::shared_ptr<const CachedScene> adopt(const std::string& scene_hash, Job job, Scene scene,
                                           std::shared_ptr<ModelLibrary> models);

  // The scheduler at `address` (one of options.schedulers) registered this worker as
  // `scheduler_id`: the assets of its calls are fetched there first.
  void scheduler_registered(const std::string& scheduler_id, const std::string& address);

  int threads() const { return pool_.size(); }
  const SceneCache& scene_cache() const { return cache_; }
  const AssetStore& asset_store() const { return store_; }
  // RenderTile calls that returned a tile (OK), since start.
  std::uint64_t tiles_rendered() const { return tiles_rendered_.load(); }

 private:
  // `scheduler_id`: the calling scheduler's, where missing assets are fetched first.
  std::shared_ptr<const CachedScene> prepare(const v1::JobSpec& spec, const std::string& hash,
                                             const std::string& scheduler_id);
  // Frame `frame` of the job `base` was prepared for (base itself when that is its frame), its
  // models and BVHs shared with base. InputError for a frame the job does not render.
  SceneCache::Lookup frame_of(const std::string& hash, const SceneCache::Lookup& base, int frame,
                              const SceneCache::Cancelled& cancelled);
  // The body of render(): logs nothing, render() logs what it returns.
  grpc::Status render_rect(const v1::RenderTileRequest& request, TileBuffer& pixels,
                           v1::TileStats& stats, const RenderControl& control, TileBuffer* film);
  void log_call(const v1::RenderTileRequest& request, const grpc::Status& status,
                const v1::TileStats& stats) const;

  std::shared_ptr<spdlog::logger> log_;
  std::filesystem::path cache_dir_;
  AssetStore store_;
  std::unique_ptr<AssetFetcher> fetcher_;  // null without a scheduler
  SceneCache cache_;
  ThreadPool pool_;  // the render threads every call shares
  std::atomic<std::uint64_t> tiles_rendered_{0};
};

}  // namespace farm
