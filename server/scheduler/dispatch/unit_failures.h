#pragma once
// What becomes of a batch that did not come back right (docs/architecture.md, "The end of the job,
// and the failure paths"), pulled out of the dispatcher: an attempt charged to its units, a
// lost-worker attempt, or neither (the worker's own failure); the worker kept off the job or
// backed off (worker_failures.h); the job's watchers told (TileFailed); the job failed when its
// units run out of attempts or every worker of the farm is kept off it. And the answers that are
// the worker's alone: its disk full (a backoff, no attempt counted), and a result no engine makes
// (the worker quarantined, unless a second worker makes the same kind: then it is the job's own).
//
// Lock: mutex_ is a leaf (the impossible results, the disk-full backoffs); WorkerFailures has its
// own. Neither is held while the store, the registry, the events or the dispatcher are called.
#include <grpcpp/grpcpp.h>
#include <spdlog/logger.h>

#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "server/common/retry_backoff.h"
#include "server/scheduler/dispatch/unit_metrics.h"
#include "server/scheduler/dispatch/worker_failures.h"
#include "server/scheduler/events/job_events.h"
#include "server/scheduler/jobs/finisher.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/workers/tile_worker.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

// What the failure accounting and the spot checks ask of the dispatcher that owns them.
class DispatchControl {
 public:
  // The batch (running on worker_id) back in the queue with no attempt counted, once the store
  // takes it.
  virtual void requeue_when_stored(const UnitBatch& batch, const std::string& worker_id) = 0;
  // Settles the spot checks no available worker is left to take.
  virtual void settle_stranded() = 0;
  // A failed job's calls in flight cancelled and its batches waiting for a check dropped.
  virtual void stop_job(const std::string& job_id) = 0;
  // The worker gets no more units (Dispatcher::quarantine).
  virtual void quarantine(const std::string& worker_id, const std::string& worker, const std::string& reason) = 0;
  // Wakes the slots: units are back in the queue.
  virtual void wake() = 0;
  // The batch's result kept: its pixels to the frame, its units marked done (Dispatcher::keep).
  virtual void keep(const std::string& worker_id, const std::string& worker, const UnitBatch& batch,
                    RenderedTiles& result) = 0;
  // The settings of the batch's job at its pass; nullopt (logged) when the job is gone.
  virtual std::optional<RenderSettings> settings_of(const UnitBatch& batch) = 0;

 protected:
  ~DispatchControl() = default;
};

class UnitFailures {
 public:
  // Each part outlives this.
  struct Parts {
    const SchedulerOptions& options;
    JobStore& store;
    JobEvents& events;
    WorkerRegistry& workers;
    Finisher& finisher;
    UnitMetrics& metrics;
    spdlog::logger& log;
    DispatchControl& control;
  };
  explicit UnitFailures(const Parts& parts);

  // A call of `w` for `batch` ended without a result: `left` (the reason) when the registry
  // dropped the worker meanwhile, else as `status` says (deadline, disk full, unreachable, or an
  // error of the worker's or the unit's).
  void call_failed(WorkerEntry& w, const UnitBatch& batch, const grpc::Status& status,
                   const std::optional<std::string>& left);
  // A reply that failed the result check (`problem`): the worker is quarantined, unless another
  // worker already rendered the job to the same kind of impossible value, which makes it the
  // job's own: then the job fails saying so, and that worker is released.
  void impossible_result(WorkerEntry& w, const UnitBatch& batch, const std::string& problem);
  // Counts a failed attempt on the batch (running on worker_id) with `why`, tells the job's
  // watchers, and fails the job at max_attempts.
  void fail(const std::string& worker_id, const std::string& worker, const UnitBatch& batch, const std::string& why,
            int max_attempts);
  // Tells the job's watchers (and its log) that units first .. first + count - 1 failed on `worker`.
  void announce(const std::string& job_id, std::uint32_t first, std::uint32_t count, const std::string& worker,
                const std::string& why, bool will_retry);
  // A batch of the worker was kept: its run of failures ends, and its disk had room.
  void kept(const std::string& worker_id);

  // Whether the worker is kept off the job, and the jobs it is kept off (worker_failures.h).
  bool blocked(const std::string& worker_id, const std::string& job_id) const;
  std::vector<std::string> blocked_jobs(const std::string& worker_id) const;
  // The job ended, or the worker left for good: what was remembered of it goes.
  void forget_job(const std::string& job_id);
  void forget_worker(const std::string& worker_id);

 private:
  // A failure of `kind` on `w` accounted as WorkerFailures says: an attempt charged to the batch
  // (fail) or the batch queued again uncharged, the worker kept off the job or backed off; the
  // job fails when every worker of the farm is kept off it.
  void charge(WorkerEntry& w, const UnitBatch& batch, const std::string& why, FailureKind kind);
  // Not the unit's own failure (the worker's): the batch queued again with no attempt counted,
  // the failure logged and announced as TileFailed.
  void uncharged(WorkerEntry& w, const UnitBatch& batch, const std::string& why);
  // The batch's worker was lost while it rendered: a lost-worker attempt counted instead of a
  // failed one (max_lost_worker_attempts), otherwise as fail.
  void lose(const std::string& worker_id, const std::string& worker, const UnitBatch& batch, const std::string& why);
  // What fail and lose do once the store has counted: the watchers told, and a job that failed
  // by it ended here.
  void after_failure(const std::string& worker, const UnitBatch& batch, const std::string& why, v1::JobState before,
                     const TileFailure& failure);
  // The worker said its disk is full: its batch queued again (no attempt counted) and the worker
  // left alone for its backoff.
  void worker_disk_full(WorkerEntry& w, const UnitBatch& batch, const grpc::Status& status);
  // Whether every worker not quarantined is kept off the job (and there is one).
  bool every_worker_blocked(const std::string& job_id) const;

  const SchedulerOptions& options_;
  JobStore& store_;
  JobEvents& events_;
  WorkerRegistry& workers_;
  Finisher& finisher_;
  UnitMetrics& metrics_;
  spdlog::logger& log_;
  DispatchControl& control_;
  WorkerFailures failures_;  // its own lock (a leaf)
  mutable std::mutex mutex_;
  // The first impossible result of each active job (impossible_result): who, and its kind.
  struct ImpossibleResult {
    std::string worker_id, worker, kind;
  };
  std::map<std::string, ImpossibleResult> impossible_;
  std::map<std::string, RetryBackoff> worker_disk_full_;  // by worker id, while its disk is full
};

}  // namespace farm
