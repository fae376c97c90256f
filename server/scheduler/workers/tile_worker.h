#pragma once
// What the scheduler's dispatcher renders tiles on: a remote `farm worker` over gRPC here, or
// the same TileRenderer in this process (server/embedded/in_process_tile_worker.h, what
// `farm render` runs). Both run TileRenderer::render in the end, so a tile's pixels do not
// depend on the route.
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "renderer/image/tile_buffer.h"
#include "server/common/client_identity.h"
#include "server/scheduler/assets/asset_grants.h"

namespace farm {

// Stops one render call from another thread (a cancelled job, a worker that left).
class TileCancel {
 public:
  void cancel();
  bool cancelled() const { return cancelled_.load(); }
  // Runs `hook` on cancel() (at once if already cancelled); cleared with nullptr, which returns
  // only once a hook already running has finished. The hook must not call back into this object.
  void set_hook(std::function<void()> hook);

 private:
  std::atomic<bool> cancelled_{false};
  std::mutex mutex_;
  std::function<void()> hook_;
};

// What a render call brings back: its statistics, and the pixels either encoded (TileData in the
// response, from a remote worker) or as they were rendered (from a worker in this process, which
// need not encode what the scheduler would only decode again).
struct RenderedTiles {
  v1::RenderTileResponse response;
  std::optional<TileBuffer> pixels;
  // Handed to the call by the dispatcher when the frame's film is kept in this process
  // (FrameAssembly::film_to_render_into): a worker in this process may paste the batch's pixels
  // straight into it, and says so with `in_film` (no `pixels` then). The call holds the film
  // alive; a remote worker ignores it.
  std::shared_ptr<TileBuffer> film;
  bool in_film = false;
};

class TileWorker {
 public:
  virtual ~TileWorker() = default;
  // Blocking: renders `request` before `deadline`, or stops with CANCELLED once `cancel` fires.
  virtual grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                              std::chrono::system_clock::time_point deadline,
                              TileCancel& cancel) = 0;
  // Waits up to `timeout` for the worker to answer: a down or suspect worker is probed with this
  // before it gets tiles again.
  virtual bool probe(std::chrono::milliseconds timeout) = 0;
  // Does not block: false while the worker cannot be reached at all (no connection yet; a remote
  // worker is asked to connect), so that nobody waits on a probe that cannot succeed.
  virtual bool connected() { return true; }
  virtual std::string describe() const = 0;  // for messages: the address, or "in-process"
};

// How the scheduler reaches a remote worker: as whom (its token and TLS), and the grants that
// let the worker fetch the assets of the calls it is given.
struct WorkerLink {
  ClientIdentity identity;
  std::string worker_name;        // the name it registered under; empty for a static worker
  AssetGrants* grants = nullptr;  // null: no grants (a scheduler without tokens lets anyone fetch)
};

// A `farm worker` at host:port, through the generated farm.v1.Worker stub.
class RemoteTileWorker final : public TileWorker {
 public:
  explicit RemoteTileWorker(std::string address, WorkerLink link = {});
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override;
  bool probe(std::chrono::milliseconds timeout) override;
  bool connected() override;
  std::string describe() const override { return address_; }

 private:
  std::string address_;
  WorkerLink link_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Worker::Stub> stub_;
};

}  // namespace farm
