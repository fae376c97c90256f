#pragma once
// The embedded farm's worker: the scheduler core hands it tiles like any TileWorker, and it
// renders them on a TileRenderer in this process.
#include <chrono>
#include <string>

#include "server/scheduler/workers/tile_worker.h"
#include "server/worker/tile_renderer.h"

namespace farm {

// A TileRenderer in this process: no sockets, no serialisation of the scene.
class InProcessTileWorker final : public TileWorker {
 public:
  explicit InProcessTileWorker(const TileRendererOptions& options) : renderer_(options) {}
  // The pixels come back as rendered (RenderedTiles::pixels), not encoded.
  grpc::Status render(const v1::RenderTileRequest& request, RenderedTiles& result,
                      std::chrono::system_clock::time_point deadline, TileCancel& cancel) override;
  bool probe(std::chrono::milliseconds) override { return true; }
  std::string describe() const override { return "in-process"; }
  TileRenderer& renderer() { return renderer_; }

 private:
  TileRenderer renderer_;
};

}  // namespace farm
