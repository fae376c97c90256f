// The slots, the calls in flight and their results (dispatcher.h). The spot checks' rounds are
// spot_check_rounds.cpp's, what becomes of a failed batch unit_failures.cpp's.
#include "server/scheduler/dispatch/dispatcher.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>

#include "server/common/disk_full.h"
#include "server/common/job_state.h"
#include "server/common/network_address.h"
#include "server/common/service_error.h"
#include "server/common/tile_codec.h"
#include "server/scheduler/dispatch/unit_call.h"
#include "server/common/tile_result_check.h"

namespace farm {

namespace {

// A batch never holds more tiles than this, whatever the estimate says.
constexpr int kMaxBatch = 64;
// How long an idle slot waits before it looks for work again, unless woken earlier.
constexpr auto kIdleWait = std::chrono::milliseconds(500);

}  // namespace

struct Dispatcher::InFlight {
  UnitBatch batch;
  std::string worker_id;
  // Set: the call renders `batch` (part of another worker's batch) for this spot check.
  std::shared_ptr<SpotCheck> check;
  std::shared_ptr<TileCancel> cancel = std::make_shared<TileCancel>();
  CancelReason reason = CancelReason::None;  // under Dispatcher::mutex_, with reason_text
  std::string reason_text;
};

Dispatcher::Dispatcher(const SchedulerOptions& options, const DispatcherParts& parts)
    : options_(options),
      store_(parts.store),
      assets_(parts.assets),
      assembly_(parts.assembly),
      jobs_(parts.jobs),
      events_(parts.events),
      workers_(parts.workers),
      finisher_(parts.finisher),
      pause_(parts.pause),
      outage_(parts.outage),
      setbacks_(parts.pause, parts.outage),
      log_(parts.log),
      unit_failures_(UnitFailures::Parts{options, parts.store, parts.events, parts.workers, parts.finisher, metrics_,
                                         parts.log, *this}),
      spot_checks_(SpotCheckRounds::Parts{options, parts.store, parts.workers, unit_failures_, *this, parts.log}) {}

Dispatcher::~Dispatcher() { stop(); }

template <typename Which>
void Dispatcher::cancel_calls_locked(Which&& which, CancelReason reason, const std::string& text) {
  for (const auto& call : in_flight_) {
    if (!which(*call)) continue;
    call->reason = reason;
    call->reason_text = text;
    call->cancel->cancel();
  }
}

void Dispatcher::stop() {
  std::vector<std::thread> threads;
  std::vector<std::shared_ptr<SpotCheck>> checks;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    cancel_calls_locked([](const InFlight&) { return true; }, CancelReason::Stopping);
    for (auto& [id, t] : threads_) threads.push_back(std::move(t));
    threads_.clear();
    for (std::thread& t : exited_) threads.push_back(std::move(t));
    exited_.clear();
    checks = spot_checks_.stop();
  }
  work_.notify_all();
  for (std::thread& t : threads) t.join();
  for (const auto& c : checks) store_.units().batch_requeue(c->batch.job_id, c->batch.first, c->batch.count, c->own().worker_id);
}

void Dispatcher::start_slots(const std::shared_ptr<WorkerEntry>& w) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    // Started under the lock: a slot that ends at once finds its handle in threads_.
    for (int i = 0; i < std::max(1, options_.tiles_per_worker); ++i) {
      std::thread t([this, w] { slot_main(w); });
      const std::thread::id id = t.get_id();
      threads_.emplace(id, std::move(t));
    }
  }
  join_exited();
}

void Dispatcher::join_exited() {
  std::vector<std::thread> exited;
  {
    std::lock_guard lock(mutex_);
    exited.swap(exited_);
  }
  for (std::thread& t : exited) t.join();
}

void Dispatcher::work_queued() { work_.notify_all(); }

v1::Job Dispatcher::cancel_job(const std::string& job_id) {
  // Under the dispatcher's lock, so no slot claims a tile of this job and starts it unseen.
  std::lock_guard lock(mutex_);
  v1::Job after = store_.jobs().cancel_job(job_id, unix_ms_now());
  stop_job_locked(job_id);
  return after;
}

std::map<std::string, std::vector<std::string>> Dispatcher::calls_in_flight() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, std::vector<std::string>> calls;
  for (const std::shared_ptr<InFlight>& call : in_flight_) {
    calls[call->worker_id].push_back(fmt::format("{} {} (frame {}, pass {}){}", call->batch.job_id,
                                                 describe(call->batch), call->batch.frame, call->batch.pass,
                                                 call->check ? ", a spot check" : ""));
  }
  for (auto& [id, list] : calls) std::sort(list.begin(), list.end());
  return calls;
}

void Dispatcher::job_ended_elsewhere(const std::string& job_id) { stop_job(job_id); }

void Dispatcher::stop_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  stop_job_locked(job_id);
}

void Dispatcher::stop_job_locked(const std::string& job_id) {
  unit_failures_.forget_job(job_id);
  cancel_calls_locked([&](const InFlight& call) { return call.batch.job_id == job_id; }, CancelReason::JobCancelled);
  spot_checks_.drop_job(job_id);
}

void Dispatcher::worker_left(const std::string& worker_id, const std::string& reason) {
  unit_failures_.forget_worker(worker_id);  // its id is never given again
  {
    std::lock_guard lock(mutex_);
    cancel_calls_locked([&](const InFlight& call) { return call.worker_id == worker_id; },
                        CancelReason::WorkerLeft, reason);
  }
  settle_stranded();
  work_.notify_all();
}

void Dispatcher::quarantine(const std::string& worker_id, const std::string& worker, const std::string& reason) {
  // The registry first: from now on no slot claims for the worker, and every call it has in
  // flight is in in_flight_, cancelled below.
  if (!workers_.quarantine(worker_id, reason)) return;
  {
    std::lock_guard lock(mutex_);
    cancel_calls_locked([&](const InFlight& call) { return call.worker_id == worker_id; },
                        CancelReason::Quarantined, reason);
    spot_checks_.drop_worker(worker_id);  // its own batches: the store takes their units back below
  }
  // Its tiles running (calls, batches held for a check) and its done tiles of running jobs go
  // back to the queue in one transaction: a result of it that is being kept right now either
  // finds its tiles no longer running, or is taken back here.
  for (const UnitBatch& b : store_.units().quarantine_worker(worker_id)) {
    assembly_.discard(b.job_id, b.first);
    finisher_.parts_taken_back(b.job_id);
    const std::string why =
        fmt::format("the result of worker {} is discarded and rendered again: the worker is quarantined ({})",
                    worker, reason);
    log_.warn("job {} {}: {}", b.job_id, describe(b), why);
    unit_failures_.announce(b.job_id, b.first, b.count, worker, why, true);
  }
  settle_stranded();
  work_.notify_all();
}

// ---- Slots ---------------------------------------------------------------------------------------

void Dispatcher::slot_main(const std::shared_ptr<WorkerEntry>& w) {
  slot_loop(w);
  std::lock_guard lock(mutex_);
  // stop() may have taken the handle already, to join it itself.
  if (auto it = threads_.find(std::this_thread::get_id()); it != threads_.end()) {
    exited_.push_back(std::move(it->second));
    threads_.erase(it);
  }
}

void Dispatcher::slot_loop(const std::shared_ptr<WorkerEntry>& w) {
  while (workers_.await_up(*w)) {
    bool store_answered = false;
    const std::shared_ptr<InFlight> call = claim(*w, store_answered);
    // Outside claim's lock: the end of an outage looks at every active job (StoreOutage::on_back).
    if (store_answered) outage_.answered();
    if (!call) {
      {
        std::lock_guard lock(mutex_);
        if (stopping_) return;
      }
      join_exited();  // an idle moment: the slots of workers that left are joined
      continue;  // no work yet, or the worker went down: await_up says which
    }
    RenderedTiles result;
    // Not the job's fault nor the worker's: the call goes back, a check to the checks' queue
    // (another worker checks it once dispatch resumes), a batch to the store's queue once the
    // store takes it (tiles it marked done meanwhile stay done).
    const auto put_back = [&] {
      if (call->check) {
        spot_checks_.put_back(call->check);
      } else {
        requeue_when_stored(call->batch, w->id);
      }
    };
    if (call->batch.started_job) announce_started(call->batch.job_id);
    try {
      const grpc::Status status = render(*w, *call, result);
      handle_result(*w, *call, status, result);
    } catch (const std::exception& e) {
      if (setbacks_.report_current() != Setback::none) {
        // The scheduler's own disk refused something on the way (the job's scene laid out again,
        // a mark in the store), or the store's server went away: the batch waits for them.
        put_back();
      } else {
        // Nothing may end a slot's thread (that would be std::terminate); the batch's units stay
        // as the store has them, queued again by the next scheduler to open it.
        log_.error("job {} {}: {}", call->batch.job_id, describe(call->batch), e.what());
      }
    }
    std::lock_guard lock(mutex_);
    in_flight_.erase(call);
  }
}

void Dispatcher::announce_started(const std::string& job_id) {
  try {
    events_.publish_started(job_id);
  } catch (const std::exception& e) {
    // The store away or full: watchers see it running from its next event; the batch renders.
    log_.warn("job {}: its start not announced: {}", job_id, e.what());
  }
}

std::shared_ptr<Dispatcher::InFlight> Dispatcher::claim(const WorkerEntry& w, bool& store_answered) {
  std::unique_lock lock(mutex_);
  // Checked under this lock, with the claim: a worker removed, quarantined (or marked down) after
  // this point finds the call in flight and cancels it.
  if (stopping_ || !workers_.available(w)) return nullptr;
  // A result rendered now could not be kept: nothing goes out until the disk has room again
  // (the pause's resume wakes the slots).
  if (pause_.paused()) {
    work_.wait_for(lock, kIdleWait);
    return nullptr;
  }
  // A batch waiting for a spot check goes first: its job cannot finish before it.
  if (std::shared_ptr<SpotCheck> c = spot_checks_.next_for(w.id)) {
    auto call = std::make_shared<InFlight>();
    call->batch = UnitBatch{c->batch.job_id, c->span.first, c->span.count, c->span.rect, 0};
    call->batch.frame = c->batch.frame;
    call->batch.pass = c->batch.pass;
    call->worker_id = w.id;
    call->check = c;
    in_flight_.insert(call);
    return call;
  }
  std::optional<UnitBatch> batch;
  try {
    // batch_size's answer stops changing at 2 x slots x kMaxBatch queued tiles: counted up to that.
    batch = store_.units().claim_next_batch(
        w.id, unix_ms_now(), [this](const std::string& job_id, int queued) { return batch_size(job_id, queued); },
        2 * std::max(1, workers_.slots_up()) * kMaxBatch,
        [this, &w](const std::string& job_id) { return unit_failures_.blocked(w.id, job_id); },
        WorkerOffer{w.facts.tags, w.facts.threads}, options_.whole_row_batches);
    store_answered = true;
  } catch (const std::exception& e) {
    // A setback (the store full or away): nothing was claimed; the slot asks again after its wait.
    if (setbacks_.report_current() == Setback::none) log_.error("claiming units: {}", e.what());
  }
  if (!batch) {
    work_.wait_for(lock, kIdleWait);
    return nullptr;
  }
  auto call = std::make_shared<InFlight>();
  call->batch = std::move(*batch);
  call->batch.handed_out = std::chrono::steady_clock::now();
  call->worker_id = w.id;
  in_flight_.insert(call);
  return call;
}

int Dispatcher::batch_size(const std::string& job_id, int queued_tiles) const {
  if (options_.batch_target.count() <= 0) return 1;
  const std::optional<double> ms_per_unit = jobs_.unit_cost(job_id);
  if (!ms_per_unit) return 1;  // nothing measured yet: the first tiles tell
  // The tail goes out in small pieces, so that no worker is left with a long batch while the
  // others have nothing: at most half of each slot's share of what is queued.
  const int share = queued_tiles / (2 * std::max(1, workers_.slots_up()));
  const double by_time = static_cast<double>(options_.batch_target.count()) / std::max(*ms_per_unit, 1e-3);
  return std::clamp(std::min(static_cast<int>(by_time), share), 1, kMaxBatch);
}

grpc::Status Dispatcher::render(WorkerEntry& w, const InFlight& call, RenderedTiles& result) {
  try {
    const std::shared_ptr<const JobInfo> info = jobs_.get(call.batch.job_id);
    // A reply a spot check may hold must bring its own pixels; a check's too (compared, not kept).
    if (!call.check && !spot_checks_.may_hold(w)) {
      result.film = assembly_.film_to_render_into(call.batch.job_id, info->frame(call.batch.frame));
    }
    return render_units(w, {call.batch, *info, store_.leases().scheduler(), options_.tile_deadline, *call.cancel},
                        assets_, result);
  } catch (const DiskFull&) {
    throw;  // the scheduler's disk (the job's scene laid out again): slot_loop waits for room
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
}

// ---- Results -------------------------------------------------------------------------------------

void Dispatcher::handle_result(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                               RenderedTiles& result) {
  // An answer is a sign of life as good as a heartbeat, and sooner: a worker that was stopped
  // (SIGSTOP, a machine that froze) and has just answered is not dropped a moment later for a
  // heartbeat still on its way, taking the batch it was handed next with it.
  if (status.ok()) workers_.heartbeat(w.id);
  CancelReason reason;
  std::string reason_text;
  {
    std::lock_guard lock(mutex_);
    reason = call.reason;
    reason_text = call.reason_text;
  }
  if (call.check) {
    spot_checks_.on_reply(w, call.check, status, reason, result);
    return;
  }
  if (reason == CancelReason::JobCancelled) return;  // the job is final; its tiles stay as they were
  if (status.ok() && reason != CancelReason::Quarantined) {
    accept(w, call, result);
  } else if (reason == CancelReason::Stopping || reason == CancelReason::Quarantined) {
    store_.units().batch_requeue(call.batch.job_id, call.batch.first, call.batch.count, w.id);
    work_.notify_all();
  } else {
    failed(w, call, status, reason, reason_text);
  }
}

std::optional<RenderSettings> Dispatcher::settings_of(const UnitBatch& batch) {
  try {
    RenderSettings settings = jobs_.get(batch.job_id)->job->render;
    settings.pass = batch.pass;  // what a reply for the batch renders (its samples)
    return settings;
  } catch (const std::exception& e) {
    log_.error("job {} {}: {}", batch.job_id, describe(batch), e.what());
    return std::nullopt;
  }
}

void Dispatcher::accept(WorkerEntry& w, const InFlight& call, RenderedTiles& result) {
  const UnitBatch& batch = call.batch;
  const std::string worker = w.worker->describe();
  const std::optional<RenderSettings> settings = settings_of(batch);
  if (!settings) {
    store_.units().batch_requeue(batch.job_id, batch.first, batch.count, w.id);
    return;
  }
  // Pixels from this process were rendered here (handed over, or written into the film); a reply
  // from anywhere else is checked before anything of it is kept.
  if (!result.pixels && !result.in_film) {
    if (const std::string problem = check_tile_reply(result.response, *settings, batch.rect); !problem.empty()) {
      unit_failures_.impossible_result(w, batch, problem);
      return;
    }
  }
  if (spot_checks_.hold(w, batch, *settings, result)) return;
  keep(w.id, worker, batch, result);
}
void Dispatcher::keep(const std::string& worker_id, const std::string& worker, const UnitBatch& batch,
                      RenderedTiles& result) {
  const v1::TileStats stats = result.response.stats();
  try {
    // The data first, then the mark: a done tile always has its data.
    assembly_.add(batch.job_id, jobs_.get(batch.job_id)->frame(batch.frame), {batch.first, batch.pass}, result);
    // Kept on disk, the result waits for a store that went away rather than being rendered again.
    const std::optional<bool> marked = outage_.when_answered(
        [&] { return store_.units().batch_done(batch.job_id, batch.first, batch.count, stats, worker_id); },
        [this](std::chrono::milliseconds wait) { return wait_unless_stopping(wait); });
    if (!marked) return;  // stopping: its tiles stay running, queued again by the next scheduler
    if (!*marked) {
      // The job ended, or the tiles were taken back (the worker quarantined meanwhile).
      assembly_.discard(batch.job_id, batch.first);
      work_.notify_all();
      return;
    }
    measured(batch, stats);
    unit_failures_.kept(worker_id);
    workers_.count_units(worker_id, batch.count, 0);
    metrics_.kept(batch.count, batch.handed_out);
    events_.publish(batch.job_id, [&](v1::JobEvent& event) {
      v1::TileFinished& f = *event.mutable_tile_finished();
      f.set_tile_index(batch.first);
      f.set_tile_count(batch.count);
      *f.mutable_rect() = to_proto(batch.rect);
      f.set_worker(worker);
      *f.mutable_stats() = stats;
      f.set_frame(batch.frame);
      f.set_pass(batch.pass);
    });
    pause_.written();
    finisher_.finish_if_complete(batch.job_id, batch.frame);
  } catch (const std::exception& e) {
    if (setbacks_.report_current() != Setback::none) {
      // No room to keep it, or the store away after its mark (an event, the merge): rendered
      // again once the setback clears, with no attempt counted against the job or the worker.
      // Logged by the pause or the outage, once a minute at most, not once a batch.
      requeue_when_stored(batch, worker_id);
      return;
    }
    log_.error("job {} {}: keeping the result: {}", batch.job_id, describe(batch), e.what());
    store_.units().batch_requeue(batch.job_id, batch.first, batch.count, worker_id);
    work_.notify_all();
  }
}

bool Dispatcher::wait_unless_stopping(std::chrono::milliseconds wait) {
  std::unique_lock lock(mutex_);
  work_.wait_for(lock, wait, [this] { return stopping_; });
  return stopping_;
}

void Dispatcher::requeue_when_stored(const UnitBatch& batch, const std::string& worker_id) {
  while (true) {
    try {
      // A store whose server is away is asked again every second (StoreOutage::when_answered).
      const std::optional<bool> requeued = outage_.when_answered(
          [&] {
            store_.units().batch_requeue(batch.job_id, batch.first, batch.count, worker_id);
            return true;
          },
          [this](std::chrono::milliseconds wait) { return wait_unless_stopping(wait); });
      if (requeued) work_.notify_all();
      return;  // queued again, or stopping
    } catch (const DiskFull& e) {
      pause_.report(e);  // the store itself is full
    }
    std::unique_lock lock(mutex_);
    // Until the pause's prober finds room again (its resume wakes this), or the scheduler stops.
    while (!stopping_ && pause_.paused()) work_.wait_for(lock, kIdleWait);
    if (stopping_) return;
  }
}


void Dispatcher::measured(const UnitBatch& batch, const v1::TileStats& stats) {
  // What a tile costs a worker running at full speed: its threads' CPU time shared by them. The
  // call's wall time would also count the time its threads waited for a core (two workers on
  // one machine, or two calls in flight on one worker), and halve the batches for nothing.
  const double per_call = stats.cpu_ms() > 0 && stats.threads() > 0 ? stats.cpu_ms() / stats.threads()
                                                                      : stats.render_ms();
  jobs_.add_unit_cost(batch.job_id, per_call / std::max<std::uint32_t>(1, batch.count));
}

void Dispatcher::failed(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                        CancelReason reason, const std::string& reason_text) {
  unit_failures_.call_failed(w, call.batch, status,
                             reason == CancelReason::WorkerLeft ? std::optional(reason_text) : std::nullopt);
}








}  // namespace farm
