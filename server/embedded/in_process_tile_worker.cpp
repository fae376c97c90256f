#include "server/embedded/in_process_tile_worker.h"

namespace farm {

grpc::Status InProcessTileWorker::render(const v1::RenderTileRequest& request, RenderedTiles& result,
                                         std::chrono::system_clock::time_point deadline,
                                         TileCancel& cancel) {
  RenderControl control;
  control.cancelled = [&cancel] { return cancel.cancelled(); };
  control.deadline = deadline;
  TileBuffer pixels;
  const grpc::Status status =
      renderer_.render(request, pixels, *result.response.mutable_stats(), control, result.film.get());
  if (!status.ok()) return status;
  // An OK call without pixels of its own wrote them into the film (TileRenderer::render).
  if (result.film && pixels.rect().empty()) {
    result.in_film = true;
  } else {
    result.pixels = std::move(pixels);
  }
  return status;
}

}  // namespace farm
