#pragma once
// farm.v1.Worker: renders rectangles of jobs' frames through the engine contract.
//
// Built on gRPC's synchronous API. A RenderTile call is seconds of CPU work followed by one
// reply, so a blocking handler that queues its sub-tiles on the shared render ThreadPool and waits
// (polling for cancellation and the deadline) is the simplest correct shape; the callback API
// would save the handler threads, but those only sleep while the pool's threads render, and
// their number is bounded by the calls in flight.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/access_control.h"
#include "server/common/client_identity.h"
#include "server/worker/tile_renderer.h"

namespace farm {

struct WorkerOptions {
  std::string listen;                  // host:port; port 0 = any free port
  int threads = 0;                     // render threads; 0 = all hardware threads
  // host:port of each scheduler it serves: registered with, assets fetched from; none: none.
  std::vector<std::string> schedulers;
  // What it offers the schedulers it registers with (--tag): jobs whose requirements name tags
  // go only to workers with all of them.
  std::vector<std::string> tags;
  std::filesystem::path cache_dir;     // blobs/ and scenes/ live here
  std::size_t max_scenes = 8;          // prepared scenes kept in memory
  std::uint64_t cache_memory_mb = 4096;  // approximate memory budget of the prepared scenes
  // Who may call RenderTile (roles scheduler or admin); default: anyone (loopback).
  AccessControl access;
  ClientIdentity scheduler_identity;     // token and TLS for the calls to the schedulers
};

class WorkerService final : public v1::Worker::Service {
 public:
  explicit WorkerService(const WorkerOptions& options);

  grpc::Status RenderTile(grpc::ServerContext* context, const v1::RenderTileRequest* request,
                          v1::RenderTileResponse* response) override;

  int threads() const { return renderer_.threads(); }
  // See TileRenderer::scheduler_registered.
  void scheduler_registered(const std::string& scheduler_id, const std::string& address) {
    renderer_.scheduler_registered(scheduler_id, address);
  }
  const SceneCache& scene_cache() const { return renderer_.scene_cache(); }
  TileRenderer& renderer() { return renderer_; }

 private:
  AccessControl access_;
  TileRenderer renderer_;  // the handler's body, shared with the scheduler's in-process worker
};

}  // namespace farm
