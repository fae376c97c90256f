#include "server/embedded/in_process_tile_worker.h"

namespace farm {

grpc::Status InProcessTileWorker::render(const v1::RenderTileRequest& request,
                                         v1::RenderTileResponse& response,
                                         std::chrono::system_clock::time_point deadline,
                                         TileCancel& cancel) {
  RenderControl control;
  control.cancelled = [&cancel] { return cancel.cancelled(); };
  control.deadline = deadline;
  return renderer_.render(request, response, control);
}

}  // namespace farm
