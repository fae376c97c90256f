#pragma once
// The rounds of a spot check (`--verify-fraction`, spot_checks.h), pulled out of the dispatcher:
// a batch holding chosen units is held, not done, while other workers render its chosen span;
// their opinions are weighed (judge) and the check settled: the batch kept, or failed and the
// workers that disagree quarantined. A check no available worker is left to take is settled as it
// stands: kept unchecked with one opinion, failed with two that differ.
//
// The dispatcher's slots hand a held check to a worker (next_for) the way they claim a batch,
// and give the check's reply back here (on_reply); what is kept, failed or quarantined goes back
// through DispatchControl (unit_failures.h) and UnitFailures.
//
// Lock: mutex_ guards checks_ and the checks in it (queued, asked, opinions). Taken under the
// dispatcher's lock (claim, quarantine, stop, a job stopped); under it only the worker registry's
// (is another worker available?). Nothing is kept, failed, quarantined or logged under it.
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <spdlog/logger.h>

#include "server/scheduler/dispatch/cancel_reason.h"
#include "server/scheduler/dispatch/spot_checks.h"
#include "server/scheduler/dispatch/unit_failures.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/workers/tile_worker.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

// A batch whose reply waits, its units still running in the store on its worker, until another
// worker's rendering of its chosen span agrees. Under SpotCheckRounds::mutex_ while held there.
struct SpotCheck {
  UnitBatch batch;
  UnitSpan span;
  RenderedTiles reply;            // the batch's worker's, kept if the check agrees
  std::vector<Opinion> opinions;  // opinions[0]: the batch's worker's pixels of the span
  std::set<std::string> asked;    // workers that rendered it or failed to: not asked again
  bool queued = true;             // waiting for a slot (false: a call renders it)

  const Opinion& own() const { return opinions.front(); }
};

class SpotCheckRounds {
 public:
  // Each part outlives this.
  struct Parts {
    const SchedulerOptions& options;
    JobStore& store;
    WorkerRegistry& workers;
    UnitFailures& failures;
    DispatchControl& control;
    spdlog::logger& log;
  };
  explicit SpotCheckRounds(const Parts& parts);

  // A checked, OK reply to `batch` from worker `w`: held for a check of its chosen span, or
  // queued again when the rounds are stopped (true: taken care of, the reply taken); false when
  // nothing of it is chosen or no other worker is there to check it on: keep it now.
  bool hold(const WorkerEntry& w, const UnitBatch& batch, const RenderSettings& settings, RenderedTiles& result);
  // Whether hold() may keep a reply of this worker's for a check (spot checks on for its host):
  // such a reply must come back as pixels of its own, not written into the frame's film.
  bool may_hold(const WorkerEntry& w) const;
  // A held check for worker `worker_id` to render (one it has not rendered or failed), now taken;
  // null when there is none. The batch to render is the check's span.
  std::shared_ptr<SpotCheck> next_for(const std::string& worker_id);
  // A check's call that could not run (a setback): the check waits for a slot again.
  void put_back(const std::shared_ptr<SpotCheck>& check);
  // The reply of worker `w`'s call rendering `check`'s span, `reason` why the scheduler cancelled
  // it (if it did).
  void on_reply(WorkerEntry& w, const std::shared_ptr<SpotCheck>& check, const grpc::Status& status,
                CancelReason reason, RenderedTiles& result);
  // Settles the checks that no available worker is left to take.
  void settle_stranded();

  // The job's held checks dropped (the job ended: its units stay as the store has them).
  void drop_job(const std::string& job_id);
  // The worker quarantined: the checks of its own batches dropped (the store takes their units
  // back), its opinions of others' struck out.
  void drop_worker(const std::string& worker_id);
  // Stopping: every held check handed back to be queued again, and none held from now on.
  std::vector<std::shared_ptr<SpotCheck>> stop();

 private:
  // What `j` (an agreement) decides about `check`, which is no longer held.
  void settle(SpotCheck& check, const Judgement& j, const Opinion& agreeing);
  bool holds_locked(const std::shared_ptr<SpotCheck>& check) const;
  const SpotCheckChooser& chooser_for(const WorkerEntry& w) const;

  const SchedulerOptions& options_;
  JobStore& store_;
  WorkerRegistry& workers_;
  UnitFailures& failures_;
  DispatchControl& control_;
  spdlog::logger& log_;
  SpotCheckChooser chooser_;         // workers on this host
  SpotCheckChooser remote_chooser_;  // workers on other hosts
  mutable std::mutex mutex_;
  std::list<std::shared_ptr<SpotCheck>> checks_;  // held, waiting for a check
  bool stopped_ = false;
};

}  // namespace farm
