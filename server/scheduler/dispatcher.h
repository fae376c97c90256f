#pragma once
// Tiles out to workers and their results back.
//
// Every worker gets `tiles_per_worker` slots, each a thread that claims the next queued batch of
// tiles (JobStore::claim_next_batch: priority, then submission order, then tile index), renders
// it on its worker in one call with a deadline per tile, keeps the result (FrameAssembly) and
// then marks the tiles done. A batch holds as many consecutive tiles of a grid row as make about
// `batch_target` of rendering by the job's measured tile costs (the worker threads' CPU time per
// tile, divided by the threads; one tile until a cost is known, and smaller batches toward the
// end of a job), so cheap tiles do not drown in per-call costs.
// A failed or late batch goes back to the queue with attempts + 1 and the reason (a tile that
// failed goes out alone from then on); at max_attempts the job fails with it. A worker that
// cannot be reached, or misses a deadline, is marked down in the registry until it answers a
// probe. A job whose tiles are all done goes to the Finisher.
//
// Lock: Dispatcher::mutex_ guards stopping_, threads_ and the calls in flight (each one's cancel
// reason). A batch is claimed, and a job cancelled in the store, under it, so that cancel_job(),
// worker_left() and stop() see every call a slot has started, and no slot claims for a worker
// the registry has removed. Taken under it: the job store's lock and, within that (the store
// asking for a batch size), the worker registry's and RunningJobs'; the registry's also directly
// (is the worker available?), and each call's TileCancel. None of those is held while it is
// taken; results are handled, events published and jobs finished without it.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/logger.h>

#include "proto/farm.pb.h"
#include "server/common/asset_store.h"
#include "server/scheduler/finisher.h"
#include "server/scheduler/frame_assembly.h"
#include "server/scheduler/job_events.h"
#include "server/scheduler/running_jobs.h"
#include "server/scheduler/scheduler_options.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/tile_worker.h"
#include "server/scheduler/worker_registry.h"

namespace farm {

// What the dispatcher works with; each part outlives it.
struct DispatcherParts {
  JobStore& store;
  const AssetStore& assets;
  FrameAssembly& assembly;
  RunningJobs& jobs;
  JobEvents& events;
  WorkerRegistry& workers;
  Finisher& finisher;
  spdlog::logger& log;
};

class Dispatcher {
 public:
  Dispatcher(const SchedulerOptions& options, const DispatcherParts& parts);
  ~Dispatcher();  // stop()
  Dispatcher(const Dispatcher&) = delete;
  Dispatcher& operator=(const Dispatcher&) = delete;

  // Starts the worker's slots (none once stopping).
  void start_slots(const std::shared_ptr<WorkerEntry>& w);
  // Wakes the slots waiting for work: a job was queued.
  void work_queued();
  // Cancels the job in the store and its calls in flight; their tiles stay as they are. Returns
  // the job as the store has it now.
  v1::Job cancel_job(const std::string& job_id);
  // Cancels the worker's calls in flight: their tiles are retried on others (an attempt counted).
  void worker_left(const std::string& worker_id, const std::string& reason);
  // Cancels every call in flight, their tiles queued again without an attempt counted, and joins
  // the slots. Idempotent.
  void stop();

 private:
  // Why a call in flight was cancelled by the scheduler, which decides what becomes of its tiles.
  enum class CancelReason { None, JobCancelled, WorkerLeft, Stopping };
  struct InFlight;

  void slot_loop(const std::shared_ptr<WorkerEntry>& w);
  // The next batch for `w`, in flight from now on; null when there was none (after a wait).
  std::shared_ptr<InFlight> claim(const WorkerEntry& w);
  int batch_size(const std::string& job_id, int queued_tiles) const;  // called back by claim
  grpc::Status render(WorkerEntry& w, const InFlight& call, RenderedTiles& result);
  void handle_result(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                     RenderedTiles& result);
  void keep(const WorkerEntry& w, const TileBatch& batch, RenderedTiles& result);
  void measured(const TileBatch& batch, const v1::TileStats& stats);  // a batch's cost per tile
  void failed(WorkerEntry& w, const InFlight& call, const grpc::Status& status, CancelReason reason,
              const std::string& reason_text);
  // Cancels the calls in flight that `which` picks, for `reason`.
  template <typename Which>
  void cancel_calls_locked(Which&& which, CancelReason reason, const std::string& text = {});

  const SchedulerOptions& options_;
  JobStore& store_;
  const AssetStore& assets_;
  FrameAssembly& assembly_;
  RunningJobs& jobs_;
  JobEvents& events_;
  WorkerRegistry& workers_;
  Finisher& finisher_;
  spdlog::logger& log_;
  mutable std::mutex mutex_;
  std::condition_variable work_;  // a job queued, a batch back in the queue, stopping
  bool stopping_ = false;
  std::vector<std::thread> threads_;  // slots of every worker ever added
  std::set<std::shared_ptr<InFlight>> in_flight_;
};

}  // namespace farm
