#include "server/scheduler/dispatch/unit_failures.h"

#include <fmt/format.h>

#include <algorithm>

#include "server/common/disk_full.h"
#include "server/common/job_state.h"
#include "server/common/service_error.h"

namespace farm {

namespace {

// How a worker's error answer to RenderTile is accounted (worker_failures.h): a refusal is never
// the unit's fault; INVALID_ARGUMENT says the unit can never render.
FailureKind failure_kind(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::INVALID_ARGUMENT: return FailureKind::NeverRenders;
    case grpc::StatusCode::UNIMPLEMENTED:  // not a worker at all (a scheduler's own address)
    case grpc::StatusCode::UNAUTHENTICATED:
    case grpc::StatusCode::PERMISSION_DENIED:
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::NOT_FOUND:
    case grpc::StatusCode::CANCELLED:
    case grpc::StatusCode::ABORTED: return FailureKind::Refused;
    default: return FailureKind::Unit;
  }
}

// The kind of impossible value a result check found: its plane ("rgba plane", "depth plane",
// "stats"), without the pixel and the value: what two workers' results must share to agree.
// Empty for a reply malformed in its shape (rect, plane sizes), which only a worker gets wrong.
std::string value_problem_kind(const std::string& problem) {
  std::string_view rest = problem;
  if (rest.rfind("pixel (", 0) == 0) {
    const std::size_t colon = rest.find("): ");
    if (colon == std::string_view::npos) return {};
    rest.remove_prefix(colon + 3);
  } else if (rest.rfind("stats: ", 0) != 0) {
    return {};
  }
  return std::string(rest.substr(0, rest.find(':')));
}

}  // namespace

UnitFailures::UnitFailures(const Parts& parts)
    : options_(parts.options),
      store_(parts.store),
      events_(parts.events),
      workers_(parts.workers),
      finisher_(parts.finisher),
      metrics_(parts.metrics),
      log_(parts.log),
      control_(parts.control),
      failures_(WorkerFailures::Options{parts.options.job_failures_per_worker, parts.options.worker_backoff,
                                        parts.options.worker_backoff_max}) {}

void UnitFailures::call_failed(WorkerEntry& w, const UnitBatch& batch, const grpc::Status& status,
                               const std::optional<std::string>& left) {
  const std::string worker = w.worker->describe();
  std::string why;
  bool went_down = false;
  // The worker, not the tile: its process died or it stopped answering.
  bool worker_lost = false;
  if (left) {
    why = fmt::format("worker {} left: {}", worker, *left);
    worker_lost = true;
  } else if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) {
    why = fmt::format("worker {}: no result within the tile deadline of {} ms{}", worker,
                      options_.tile_deadline.count(),
                      batch.count > 1 ? fmt::format(" (x {} units)", batch.count) : std::string());
    // Slow or hung? It gets no more tiles until it answers a health check: a hung one would
    // otherwise take tile after tile to its deadline.
    workers_.mark_down(w, std::chrono::milliseconds(0));
    went_down = true;
  } else if (is_disk_full(status)) {
    worker_disk_full(w, batch, status);  // the worker's disk, not the job: no attempt counted
    return;
  } else {
    // Every failure says why, even a worker's that said nothing (a server that is no worker).
    why = fmt::format("worker {}: {}: {}", worker, status_code_name(status.error_code()),
                      status.error_message().empty() ? "(it gave no reason)" : status.error_message());
    if (status.error_code() != grpc::StatusCode::UNAVAILABLE) {
      charge(w, batch, why, failure_kind(status.error_code()));
      return;
    }
    workers_.mark_down(w, options_.probe_interval);
    went_down = true;
    worker_lost = true;
  }
  if (worker_lost) {
    lose(w.id, worker, batch, why);
  } else {
    fail(w.id, worker, batch, why, options_.max_attempts);
  }
  if (went_down) control_.settle_stranded();  // a check that only this worker could have taken
}

void UnitFailures::impossible_result(WorkerEntry& w, const UnitBatch& batch, const std::string& problem) {
  const std::string worker = w.worker->describe();
  const std::string kind = value_problem_kind(problem);
  std::optional<ImpossibleResult> earlier;
  if (!kind.empty()) {
    std::lock_guard lock(mutex_);
    const auto it = impossible_.find(batch.job_id);
    if (it == impossible_.end()) {
      impossible_.emplace(batch.job_id, ImpossibleResult{w.id, worker, kind});
    } else if (it->second.worker_id != w.id && it->second.kind == kind) {
      earlier = it->second;
    }
  }
  if (earlier) {
    // Two workers rendered the job to the same impossible values: a property of the job (an engine
    // bug it meets), not of either worker. The job ends saying so; the farm goes on, and the
    // worker quarantined for it first is released.
    const std::string why = fmt::format(
        "workers {} and {} both rendered this job to values no engine should make ({}: {}); it is the job's own, "
        "not the workers': no worker is quarantined for it (report it with the job file)",
        earlier->worker, worker, describe(batch), problem);
    fail(w.id, worker, batch, why, 1);
    if (workers_.release_quarantine(earlier->worker_id, fmt::format("worker {} rendered job {} the same way",
                                                                     worker, batch.job_id))) {
      log_.warn("worker {} is back: its result for job {} was the job's own ({})", earlier->worker, batch.job_id,
                kind);
    }
    return;
  }
  const std::string why = fmt::format("worker {} sent a result no engine makes: {}", worker, problem);
  fail(w.id, worker, batch, why + "; the worker is quarantined", options_.max_attempts);
  control_.quarantine(w.id, worker, why);
}

void UnitFailures::worker_disk_full(WorkerEntry& w, const UnitBatch& batch, const grpc::Status& status) {
  std::chrono::milliseconds wait{0};
  bool log = false;
  int skipped = 0;
  {
    std::lock_guard lock(mutex_);
    RetryBackoff& backoff =
        worker_disk_full_.try_emplace(w.id, options_.disk_full_backoff, options_.disk_full_backoff_max).first->second;
    wait = backoff.next();
    log = backoff.log_now(skipped);
  }
  if (log) {
    log_.warn("worker {}: {}; its batches go back to the queue (no attempt counted) and it gets none for {} ms{}",
              w.worker->describe(), status.error_message(), wait.count(),
              skipped > 0 ? fmt::format(" ({} more such answers since the last report)", skipped) : "");
  }
  workers_.mark_down(w, wait);
  control_.requeue_when_stored(batch, w.id);
  control_.settle_stranded();
}

void UnitFailures::charge(WorkerEntry& w, const UnitBatch& batch, const std::string& why, FailureKind kind) {
  const std::string worker = w.worker->describe();
  const FailureCharge charge = failures_.failed(w.id, batch.job_id, kind);
  if (charge.blocked_now) {
    log_.warn("job {}: worker {} is kept off it from now on: {}", batch.job_id, worker,
              kind == FailureKind::NeverRenders ? "it says its units can never render"
                                                : fmt::format("it failed {} of its units", options_.job_failures_per_worker));
  }
  if (charge.back_off.count() > 0) {
    log_.warn("worker {} is backed off for {} ms: it {} ({})", worker, charge.back_off.count(),
              kind == FailureKind::Refused ? "refused a call" : "fails units of several jobs in a row", why);
    workers_.back_off(w, charge.back_off, why);
  }
  // Nobody left to render it: the job ends here rather than waiting for ever.
  const bool nobody_left = charge.blocked_now && every_worker_blocked(batch.job_id);
  if (charge.charge_unit || nobody_left) {
    // Two workers that each say a unit can never render agree: no need for a third.
    const int max_attempts = nobody_left                         ? 1
                             : kind == FailureKind::NeverRenders ? std::min(2, options_.max_attempts)
                                                                 : options_.max_attempts;
    fail(w.id, worker, batch, nobody_left ? why + "; every worker of the farm is kept off the job" : why,
               max_attempts);
  } else {
    uncharged(w, batch, why);
  }
  if (charge.back_off.count() > 0) control_.settle_stranded();  // a check that only this worker could have taken
}

void UnitFailures::uncharged(WorkerEntry& w, const UnitBatch& batch, const std::string& why) {
  const std::string worker = w.worker->describe();
  // Not the unit's own failure (the worker's: it fails other jobs too, or failed this one
  // before): queued again with no attempt counted, and said.
  log_.warn("job {} {}: {} (no attempt counted: the worker's failure, not the unit's)", batch.job_id, describe(batch),
            why);
  workers_.count_units(w.id, 0, batch.count);
  metrics_.failed(batch.count);
  announce(batch.job_id, batch.first, batch.count, worker, why, true);
  control_.requeue_when_stored(batch, w.id);
  control_.wake();
}

bool UnitFailures::every_worker_blocked(const std::string& job_id) const {
  bool any = false;
  for (const WorkerStatus& s : workers_.workers()) {
    if (s.quarantined) continue;
    if (!failures_.blocked(s.id, job_id)) return false;
    any = true;
  }
  return any;
}

void UnitFailures::fail(const std::string& worker_id, const std::string& worker, const UnitBatch& batch,
                            const std::string& why, int max_attempts) {
  log_.warn("job {} {}: {}", batch.job_id, describe(batch), why);
  workers_.count_units(worker_id, 0, batch.count);
  metrics_.failed(batch.count);
  const std::optional<v1::Job> job = store_.jobs().get_job(batch.job_id);
  if (!job) return;
  const v1::JobState before = job->state();
  const TileFailure failure =
      store_.units().batch_failed(batch.job_id, batch.first, batch.count, why, max_attempts, unix_ms_now(), worker_id);
  after_failure(worker, batch, why, before, failure);
}

void UnitFailures::lose(const std::string& worker_id, const std::string& worker, const UnitBatch& batch,
                            const std::string& why) {
  log_.warn("job {} {}: {} (its worker was lost: no attempt counted)", batch.job_id, describe(batch), why);
  workers_.count_units(worker_id, 0, batch.count);
  metrics_.failed(batch.count);
  const std::optional<v1::Job> job = store_.jobs().get_job(batch.job_id);
  if (!job) return;
  const v1::JobState before = job->state();
  const TileFailure failure = store_.units().batch_lost(batch.job_id, batch.first, batch.count, why,
                                                options_.max_lost_worker_attempts, unix_ms_now(), worker_id);
  after_failure(worker, batch, why, before, failure);
}

void UnitFailures::after_failure(const std::string& worker, const UnitBatch& batch, const std::string& why,
                               v1::JobState before, const TileFailure& failure) {
  announce(batch.job_id, batch.first, batch.count, worker, why, failure.will_retry);
  if (failure.job.state() == v1::JOB_STATE_FAILED && before != v1::JOB_STATE_FAILED) {
    log_.error("job {} failed: {}", batch.job_id, failure.job.failure_reason());
    // Its other units in flight, and its batches waiting for a check, are of no use now.
    control_.stop_job(batch.job_id);
    events_.publish_state(failure.job, before);
    finisher_.release(batch.job_id, true);  // a retry renders its failed units only
  }
  control_.wake();
}

void UnitFailures::announce(const std::string& job_id, std::uint32_t first, std::uint32_t count,
                                  const std::string& worker, const std::string& why, bool will_retry) {
  events_.publish(job_id, [&](v1::JobEvent& event) {
    v1::TileFailed& f = *event.mutable_tile_failed();
    f.set_tile_index(first);
    f.set_tile_count(count);
    f.set_worker(worker);
    f.set_reason(why);
    f.set_will_retry(will_retry);
  });
}

void UnitFailures::kept(const std::string& worker_id) {
  failures_.succeeded(worker_id);
  std::lock_guard lock(mutex_);
  worker_disk_full_.erase(worker_id);  // its disk had room for this one
}

bool UnitFailures::blocked(const std::string& worker_id, const std::string& job_id) const {
  return failures_.blocked(worker_id, job_id);
}

std::vector<std::string> UnitFailures::blocked_jobs(const std::string& worker_id) const {
  return failures_.blocked_jobs(worker_id);
}

void UnitFailures::forget_job(const std::string& job_id) {
  failures_.forget_job(job_id);
  std::lock_guard lock(mutex_);
  impossible_.erase(job_id);
}

void UnitFailures::forget_worker(const std::string& worker_id) { failures_.forget_worker(worker_id); }

}  // namespace farm
