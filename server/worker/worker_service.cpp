#include "server/worker/worker_service.h"

#include "server/common/service_error.h"

namespace farm {

namespace {

TileRendererOptions renderer_options(const WorkerOptions& o) {
  TileRendererOptions r;
  r.blobs_dir = o.cache_dir / "blobs";
  r.cache_dir = o.cache_dir;
  r.schedulers = o.schedulers;
  r.scheduler_identity = o.scheduler_identity;
  r.threads = o.threads;
  r.max_scenes = o.max_scenes;
  r.cache_memory_mb = o.cache_memory_mb;
  return r;
}

}  // namespace

WorkerService::WorkerService(const WorkerOptions& options)
    : access_(options.access), renderer_(renderer_options(options)) {}

grpc::Status WorkerService::RenderTile(grpc::ServerContext* context,
                                       const v1::RenderTileRequest* request,
                                       v1::RenderTileResponse* response) {
  try {
    access_.require(*context, Role::scheduler | Role::admin, "RenderTile");
  } catch (const std::exception&) {
    return status_of_current_exception();
  }
  RenderControl control;
  control.cancelled = [context] { return context->IsCancelled(); };
  control.deadline = context->deadline();
  return renderer_.render(*request, *response, control);
}

}  // namespace farm
