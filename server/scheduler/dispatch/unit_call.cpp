#include "server/scheduler/dispatch/unit_call.h"

#include "server/common/read_whole_file.h"
#include "server/common/tile_codec.h"

namespace farm {

grpc::Status render_units(WorkerEntry& w, const UnitCall& call, const AssetStore& assets, RenderedTiles& result) {
  const UnitBatch& batch = call.batch;
  const v1::JobSpec& spec = *call.job.spec;
  v1::RenderTileRequest request;
  // The job text (up to --max-job-bytes) travels once per worker and scene, not with every call.
  if (!w.scenes_sent.contains(call.job.scene_hash)) *request.mutable_job() = spec;
  request.set_scene_hash(call.job.scene_hash);
  *request.mutable_rect() = to_proto(batch.rect);
  request.set_job_id(batch.job_id);
  request.set_tile_index(batch.first);
  request.set_frame(batch.frame);
  request.set_pass(batch.pass);
  request.set_scheduler_id(call.scheduler_id);
  const auto deadline = std::chrono::system_clock::now() + call.deadline_per_unit * batch.count;
  // A call again starts from an empty result, with the film it may render into (dispatcher.cpp).
  const auto fresh_result = [&result] {
    std::shared_ptr<TileBuffer> film = std::move(result.film);
    result = RenderedTiles();
    result.film = std::move(film);
  };
  grpc::Status status = w.worker->render(request, result, deadline, call.cancel);
  if (status.error_code() == grpc::StatusCode::NOT_FOUND && !request.has_job() && !call.cancel.cancelled()) {
    // The worker no longer holds the scene (evicted, or a new process at the address).
    *request.mutable_job() = spec;
    fresh_result();
    status = w.worker->render(request, result, deadline, call.cancel);
  }
  if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION && !call.cancel.cancelled()) {
    // A worker that cannot fetch the job's files (no --scheduler): once more, files inline.
    for (const v1::AssetRef& ref : spec.assets()) {
      v1::InlineAsset& asset = *request.add_assets();
      asset.set_sha256(ref.sha256());
      asset.set_data(read_whole_file(assets.path_of(ref.sha256()), "asset"));
    }
    fresh_result();
    status = w.worker->render(request, result, deadline, call.cancel);
  }
  if (status.ok() && request.has_job()) w.scenes_sent.insert(call.job.scene_hash);
  return status;
}

}  // namespace farm
