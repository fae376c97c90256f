#pragma once
// Tiles out to workers and their results back.
//
// Every worker gets `tiles_per_worker` slots, each a thread that claims the next queued batch of
// tiles (UnitQueue::claim_next_batch: priority, then submission order, then tile index), renders
// it on its worker in one call with a deadline per tile, keeps the result (FrameAssembly) and
// then marks the tiles done. A batch holds as many consecutive tiles of a grid row as make about
// `batch_target` of rendering by the job's measured tile costs (the worker threads' CPU time per
// tile, divided by the threads; one tile until a cost is known, and smaller batches toward the
// end of a job), so cheap tiles do not drown in per-call costs.
// A failed or late batch goes back to the queue with attempts + 1 and the reason (a tile that
// failed goes out alone from then on); at max_attempts the job fails with it. A batch whose
// worker was lost (the call ended UNAVAILABLE, or the worker left the registry for missed
// heartbeats) counts no attempt: it goes back with a lost-worker attempt, and the job fails only
// at max_lost_worker_attempts, so a farm whose workers die now and then loses no job to it while a
// tile that kills every worker still ends. A worker that cannot be reached, or misses a deadline,
// is marked down in the registry until it answers a probe. A job whose tiles are all done goes to
// the Finisher.
//
// Workers are not trusted. A reply that came over the wire is checked (tile_result_check.h)
// before anything of it is stored: one that fails the check fails its batch, naming the worker
// and what is wrong, and the worker is quarantined. With --verify-fraction, batches holding
// chosen tiles wait, not done, for a second worker's rendering of the chosen part
// (spot_checks.h): bit-identical, the batch is kept; different, a third worker decides and the
// worker that disagrees with it is quarantined. A quarantined worker gets no more tiles, its calls
// in flight are cancelled, and what it rendered for jobs still running is rendered again
// (UnitQueue::quarantine_worker), each batch announced as a TileFailed event naming it.
//
// The disk: a batch whose result the scheduler cannot keep for want of space (DiskFull: its file,
// or the store's mark) is queued again with no attempt counted, against neither the job nor the
// worker, and dispatch pauses (DiskFullPause: slots claim nothing until the prober finds room
// again). A worker that answers that its own disk is full (RESOURCE_EXHAUSTED "disk full in ...")
// gets its batch queued again, no attempt counted, and no tiles for a while (a backoff per
// worker, 1 s doubling to 30 s; one log line a minute for it).
//
// A worker's slots are started when it is first up (WorkerRegistry's on_first_up) and end when
// it is removed or quarantined; a slot that ended is joined by the next slot started, by an idle
// slot, or by stop(), so workers coming and going leave no threads behind.
//
// Lock: Dispatcher::mutex_ guards stopping_, the slot threads and the calls in flight (each one's
// cancel reason). A batch or a spot check is claimed, and a job cancelled in the store, under it,
// so that cancel_job(), worker_left(), quarantine() and stop() see every call a slot has started,
// and no slot claims for a worker the registry has removed or quarantined. Taken under it: the
// job store's lock and, within that (the store asking for a batch size), the worker registry's
// and RunningJobs'; the spot checks' (SpotCheckRounds, and the registry's within it); the
// registry's also directly (is the worker available?), the DiskFullPause's (is dispatch
// paused?), and each call's TileCancel. None of those is held while it is taken; results are
// handled, workers quarantined, events published and jobs finished without it. The spot checks'
// rounds are spot_check_rounds.h's; what becomes of a failed batch is unit_failures.h's; one
// call is unit_call.h's. What stays here (dispatcher.cpp, some 480 lines) is what shares mutex_:
// kept together on purpose, so that a reader of the lock sees every place it is taken.
#include <condition_variable>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/logger.h>

#include "proto/farm.pb.h"
#include "server/common/asset_store.h"
#include "server/scheduler/dispatch/cancel_reason.h"
#include "server/scheduler/dispatch/spot_check_rounds.h"
#include "server/scheduler/dispatch/unit_failures.h"
#include "server/scheduler/dispatch/unit_metrics.h"
#include "server/scheduler/events/job_events.h"
#include "server/scheduler/jobs/disk_full_pause.h"
#include "server/scheduler/jobs/finisher.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/jobs/setbacks.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/store_outage.h"
#include "server/scheduler/workers/tile_worker.h"
#include "server/scheduler/workers/worker_registry.h"

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
  DiskFullPause& pause;
  StoreOutage& outage;
  spdlog::logger& log;
};

class Dispatcher : private DispatchControl {
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
  // The job ended on another scheduler of the store (cancelled or failed there): its calls in
  // flight here are cancelled, their tiles left as the store has them.
  void job_ended_elsewhere(const std::string& job_id);
  // Units kept and failed, their rate and latency (the dashboard's /metrics).
  const UnitMetrics& metrics() const { return metrics_; }
  // The calls in flight now, by worker id: "JOB_ID units A-B (frame F, pass P)" (farm workers).
  std::map<std::string, std::vector<std::string>> calls_in_flight() const;
  // The jobs the worker is kept off for failing their units (worker_failures.h).
  std::vector<std::string> blocked_jobs(const std::string& worker_id) const {
    return unit_failures_.blocked_jobs(worker_id);
  }
  // Cancels the worker's calls in flight: their tiles are retried on others (a lost-worker attempt
  // counted, not a failed one).
  void worker_left(const std::string& worker_id, const std::string& reason);
  // The worker (its address `worker`) gets no more tiles: its calls in flight are cancelled and
  // their tiles queued again, and its results for jobs still running are thrown away and rendered
  // again. Logged, and announced to each such job as TileFailed. Nothing when it is quarantined
  // already or unknown.
  void quarantine(const std::string& worker_id, const std::string& worker, const std::string& reason) override;
  // Cancels every call in flight, their tiles queued again without an attempt counted (and the
  // batches waiting for a spot check), and joins the slots. Idempotent.
  void stop();

 private:
  struct InFlight;
  // Waits `wait` (less when woken); true when the scheduler is stopping.
  bool wait_unless_stopping(std::chrono::milliseconds wait);

  // A slot's thread: slot_loop, then its handle goes to exited_ to be joined.
  void slot_main(const std::shared_ptr<WorkerEntry>& w);
  void slot_loop(const std::shared_ptr<WorkerEntry>& w);
  // The job's first batch since it was queued was claimed: watchers and the log hear that it runs.
  void announce_started(const std::string& job_id);
  void join_exited();
  // The next batch for `w` (or a batch to check), in flight from now on; null when there was
  // none (after a wait). `store_answered`: the store answered (it may have had nothing to give).
  std::shared_ptr<InFlight> claim(const WorkerEntry& w, bool& store_answered);
  int batch_size(const std::string& job_id, int queued_tiles) const;  // called back by claim
  grpc::Status render(WorkerEntry& w, const InFlight& call, RenderedTiles& result);
  void handle_result(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                     RenderedTiles& result);
  // An OK reply to a batch: checked, then kept or held for a spot check.
  void accept(WorkerEntry& w, const InFlight& call, RenderedTiles& result);
  void settle_stranded() override { spot_checks_.settle_stranded(); }
  void keep(const std::string& worker_id, const std::string& worker, const UnitBatch& batch,
            RenderedTiles& result) override;
  void measured(const UnitBatch& batch, const v1::TileStats& stats);  // a batch's cost per tile
  void failed(WorkerEntry& w, const InFlight& call, const grpc::Status& status, CancelReason reason,
              const std::string& reason_text);
  // The batch (running on worker_id) back in the queue with no attempt counted, once the store
  // takes it: while the store itself is full, tried again each time dispatch resumes, while its
  // server is away every second (or dropped at stop(), when a restarted store queues running
  // tiles itself).
  void requeue_when_stored(const UnitBatch& batch, const std::string& worker_id) override;
  void stop_job(const std::string& job_id) override;  // under mutex_: stop_job_locked
  void wake() override { work_.notify_all(); }
  std::optional<RenderSettings> settings_of(const UnitBatch& batch) override;
  // Cancels the calls in flight that `which` picks, for `reason`.
  template <typename Which>
  void cancel_calls_locked(Which&& which, CancelReason reason, const std::string& text = {});
  // A final job's calls in flight cancelled and its batches waiting for a check dropped.
  void stop_job_locked(const std::string& job_id);

  const SchedulerOptions& options_;
  JobStore& store_;
  const AssetStore& assets_;
  FrameAssembly& assembly_;
  RunningJobs& jobs_;
  JobEvents& events_;
  WorkerRegistry& workers_;
  Finisher& finisher_;
  DiskFullPause& pause_;
  StoreOutage& outage_;
  Setbacks setbacks_;
  spdlog::logger& log_;
  UnitMetrics metrics_;
  mutable std::mutex mutex_;
  std::condition_variable work_;  // a job queued, a batch back in the queue, stopping
  bool stopping_ = false;
  std::map<std::thread::id, std::thread> threads_;  // slots running
  std::vector<std::thread> exited_;                 // slots that ended, not joined yet
  std::set<std::shared_ptr<InFlight>> in_flight_;
  UnitFailures unit_failures_;    // its own lock (a leaf)
  SpotCheckRounds spot_checks_;   // its own lock, taken under mutex_ (spot_check_rounds.h)
};

}  // namespace farm
