#pragma once
// How a scheduler core runs: read by every part of it (scheduler_core.h), set by its front ends
// (`farm scheduler`'s flags, the embedded farm of `farm render`).
#include <chrono>
#include <filesystem>
#include <functional>
#include <string>

#include "renderer/image/exr_io.h"
#include "renderer/job/job.h"
#include "renderer/loaders/model_library.h"
#include "renderer/scene/scene.h"
#include "server/common/log.h"
#include "server/scheduler/options/submit_limits.h"

namespace farm {

struct SchedulerOptions {
  std::filesystem::path data_dir;  // jobs.db, assets/, scenes/, tiles/, results/
  // The job store: empty for SQLite in data_dir/jobs.db, or a postgresql:// URL (store/job_store.h).
  std::string store;
  // On a store several schedulers share: how long this one's hold on the units it hands out
  // lasts unless renewed (scheduler_lease.h), so how long the units of a scheduler killed mid-job
  // wait before the others (or its successor) render them.
  std::chrono::milliseconds lease = std::chrono::seconds(10);
  std::chrono::milliseconds tile_deadline = std::chrono::minutes(10);
  // Final jobs older than this (since they ended) are deleted with their files (retention.h);
  // 0: kept for ever.
  std::chrono::milliseconds keep_finished{0};
  // How often waiting jobs are looked at besides when a job ends here (dependency_release.h): how
  // long a job waits after its dependency ended on another scheduler of a shared store.
  std::chrono::milliseconds dependency_sweep = std::chrono::seconds(1);
  int max_attempts = 3;            // failed attempts of one tile before its job fails
  // Workers a tile may lose while rendering it (their process died: the call ended UNAVAILABLE;
  // or they stopped heartbeating) before its job fails. Counted apart from max_attempts, since a
  // lost worker says nothing about the tile; bounded all the same, since a tile that crashes every
  // worker it is sent to would otherwise go round for ever.
  int max_lost_worker_attempts = 10;
  int tiles_per_worker = 2;        // calls in flight per worker, so it never idles between calls
  // Rendering time a call aims at; 0 sends one tile per call.
  std::chrono::milliseconds batch_target = std::chrono::milliseconds(200);
  // Units of at least this many pixels a side, each k x k of the job's tiles (unit_grid.h); 0:
  // one tile a unit. The embedded farm's, whose units cost bookkeeping and balance nothing.
  int min_unit_edge = 0;
  // A batch that begins a grid row may go on with whole rows (UnitQueue::claim_next_batch). The
  // embedded farm's, whose units are cheap and whose one worker has nobody to share them with; a
  // farm keeps its batches within a row, so that more of its workers get a share of a small job.
  bool whole_row_batches = false;
  std::chrono::milliseconds probe_interval = std::chrono::seconds(1);
  std::chrono::milliseconds heartbeat_interval = std::chrono::seconds(1);
  int missed_heartbeats = 3;       // a registered worker silent this many intervals is dropped
  // While a disk is full (the scheduler's, or a worker's), dispatch waits this long before it
  // tries again, doubling up to the maximum (disk_full_pause.h).
  std::chrono::milliseconds disk_full_backoff = std::chrono::seconds(1);
  std::chrono::milliseconds disk_full_backoff_max = std::chrono::seconds(30);
  // An UploadAsset stream that sends nothing this long is ended, its quota freed (stream_watchdog.h).
  std::chrono::milliseconds upload_idle_timeout = std::chrono::seconds(30);
  // A worker that fails this many units of one job is kept off that job (worker_failures.h).
  int job_failures_per_worker = 3;
  // A worker that fails units of several jobs in a row, or refuses calls, gets nothing this long,
  // doubling with each further failure up to the maximum (worker_failures.h).
  std::chrono::milliseconds worker_backoff = std::chrono::seconds(1);
  std::chrono::milliseconds worker_backoff_max = std::chrono::seconds(60);
  // Spot checks: this fraction of each job's tiles (at least one when > 0) is rendered again on
  // another worker and compared bit for bit before it is kept (spot_checks.h). 0: none.
  double verify_fraction = 0.0;
  // The same for workers on another host (network_address.h's on_this_host), when higher: their
  // replies crossed a network and a machine this scheduler does not run. Chosen from its cost:
  // 2% of such a worker's units rendered twice (at least one a job), the batch held until the
  // second rendering agrees (README, "Spot checks"). 0 leaves only verify_fraction.
  double remote_verify_fraction = 0.02;
  // The work one SubmitJob may start (submit_limits.h); over a limit is RESOURCE_EXHAUSTED.
  SubmitLimits limits;
  ExrPixelType exr_type = ExrPixelType::Half;  // as `farm render` without --float
  // Threads that compress a merged frame's files (0: one a core). The embedded farm of `farm
  // render --threads N` gives N: the command then uses the cores it was given, no more.
  int merge_threads = 0;
  // What the scheduler logs on stderr unless the operator chose a level (set_log_level): a
  // server logs info and up, the embedded farm of `farm render` only warnings and errors.
  LogLevel log_level = LogLevel::info;
  // The embedded farm of `farm render`: the job store lives in memory and finished tiles are
  // pasted into their frame as they arrive (InMemoryAssembly), so nothing outlives the process.
  // Off (the farm): jobs.db on disk, each batch a file before its tiles are marked done.
  bool in_memory = false;
  // The `farm` binary, run as `farm check-scene` to load each new job's scene at submit under
  // limits.max_scene_memory and max_scene_seconds (scene_check.h). Empty: the scene is built in
  // this process, as the embedded farm of `farm render` does with its user's own files.
  std::filesystem::path scene_check_program;
  // Given each job's scene as submit() built it to validate the job: the embedded farm hands it
  // to its in-process worker, so that `farm render` loads the models once, not twice.
  std::function<void(const std::string& scene_hash, const Job& job, Scene scene,
                     std::shared_ptr<ModelLibrary> models)>
      validated_scene;
};

}  // namespace farm
