#pragma once
// One RenderTile call for a batch of units, as the dispatcher's slots make it: the job's text
// sent once per worker and scene (a worker that no longer holds the scene answers NOT_FOUND and
// is sent it again), and the job's files inline for a worker that cannot fetch them
// (FAILED_PRECONDITION: it was started without --scheduler). Each unit of the batch has its
// deadline.
#include <chrono>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/common/asset_store.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/workers/tile_worker.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

struct UnitCall {
  const UnitBatch& batch;
  const JobInfo& job;
  const std::string& scheduler_id;  // a worker of several schedulers fetches the job's files here
  std::chrono::milliseconds deadline_per_unit;
  TileCancel& cancel;
};

// Renders `call.batch` on `w` into `result`. Exceptions (a blob that cannot be read for the
// inline retry) are the caller's.
grpc::Status render_units(WorkerEntry& w, const UnitCall& call, const AssetStore& assets, RenderedTiles& result);

}  // namespace farm
