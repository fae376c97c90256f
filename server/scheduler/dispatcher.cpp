#include "server/scheduler/dispatcher.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "server/common/job_state.h"
#include "server/common/read_whole_file.h"
#include "server/common/service_error.h"

namespace farm {

namespace {

v1::TileRect to_proto(const Rect& r) {
  v1::TileRect t;
  t.set_x0(r.x0);
  t.set_y0(r.y0);
  t.set_x1(r.x1);
  t.set_y1(r.y1);
  return t;
}

std::string describe(const TileBatch& batch) { return describe_tiles(batch.first, batch.count); }

// A batch never holds more tiles than this, whatever the estimate says.
constexpr int kMaxBatch = 64;
// How long an idle slot waits before it looks for work again, unless woken earlier.
constexpr auto kIdleWait = std::chrono::milliseconds(500);

}  // namespace

struct Dispatcher::InFlight {
  TileBatch batch;
  std::string worker_id;
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
      log_(parts.log) {}

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
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    cancel_calls_locked([](const InFlight&) { return true; }, CancelReason::Stopping);
    threads.swap(threads_);
  }
  work_.notify_all();
  for (std::thread& t : threads) t.join();
}

void Dispatcher::start_slots(const std::shared_ptr<WorkerEntry>& w) {
  std::lock_guard lock(mutex_);
  if (stopping_) return;
  for (int i = 0; i < std::max(1, options_.tiles_per_worker); ++i) {
    threads_.emplace_back([this, w] { slot_loop(w); });
  }
}

void Dispatcher::work_queued() { work_.notify_all(); }

v1::Job Dispatcher::cancel_job(const std::string& job_id) {
  // Under the dispatcher's lock, so no slot claims a tile of this job and starts it unseen.
  std::lock_guard lock(mutex_);
  v1::Job after = store_.cancel_job(job_id, unix_ms_now());
  cancel_calls_locked([&](const InFlight& call) { return call.batch.job_id == job_id; },
                      CancelReason::JobCancelled);
  return after;
}

void Dispatcher::worker_left(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    cancel_calls_locked([&](const InFlight& call) { return call.worker_id == worker_id; },
                        CancelReason::WorkerLeft, reason);
  }
  work_.notify_all();
}

// ---- Slots ---------------------------------------------------------------------------------------

void Dispatcher::slot_loop(const std::shared_ptr<WorkerEntry>& w) {
  while (workers_.await_up(*w)) {
    const std::shared_ptr<InFlight> call = claim(*w);
    if (!call) {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
      continue;  // no work yet, or the worker went down: await_up says which
    }
    RenderedTiles result;
    const grpc::Status status = render(*w, *call, result);
    handle_result(*w, *call, status, result);
    std::lock_guard lock(mutex_);
    in_flight_.erase(call);
  }
}

std::shared_ptr<Dispatcher::InFlight> Dispatcher::claim(const WorkerEntry& w) {
  std::unique_lock lock(mutex_);
  // Checked under this lock, with the claim: a worker removed (or marked down) after this point
  // finds the call in flight and cancels it.
  if (stopping_ || !workers_.available(w)) return nullptr;
  std::optional<TileBatch> batch;
  try {
    batch = store_.claim_next_batch(w.id, unix_ms_now(), [this](const std::string& job_id, int queued) {
      return batch_size(job_id, queued);
    });
  } catch (const std::exception& e) {
    log_.error("claiming tiles: {}", e.what());
  }
  if (!batch) {
    work_.wait_for(lock, kIdleWait);
    return nullptr;
  }
  auto call = std::make_shared<InFlight>();
  call->batch = std::move(*batch);
  call->worker_id = w.id;
  in_flight_.insert(call);
  return call;
}

int Dispatcher::batch_size(const std::string& job_id, int queued_tiles) const {
  if (options_.batch_target.count() <= 0) return 1;
  const std::optional<double> ms_per_tile = jobs_.tile_cost(job_id);
  if (!ms_per_tile) return 1;  // nothing measured yet: the first tiles tell
  // The tail goes out in small pieces, so that no worker is left with a long batch while the
  // others have nothing: at most half of each slot's share of what is queued.
  const int share = queued_tiles / (2 * std::max(1, workers_.slots_up()));
  const double by_time = static_cast<double>(options_.batch_target.count()) / std::max(*ms_per_tile, 1e-3);
  return std::clamp(std::min(static_cast<int>(by_time), share), 1, kMaxBatch);
}

grpc::Status Dispatcher::render(WorkerEntry& w, const InFlight& call, RenderedTiles& result) {
  const TileBatch& batch = call.batch;
  try {
    const std::shared_ptr<const JobInfo> info = jobs_.get(batch.job_id);
    const v1::JobSpec& spec = *info->spec;
    v1::RenderTileRequest request;
    *request.mutable_job() = spec;
    request.set_scene_hash(info->scene_hash);
    *request.mutable_rect() = to_proto(batch.rect);
    request.set_job_id(batch.job_id);
    request.set_tile_index(batch.first);
    // Each tile of the batch has its deadline.
    const auto deadline = std::chrono::system_clock::now() + options_.tile_deadline * batch.count;
    grpc::Status status = w.worker->render(request, result, deadline, *call.cancel);
    if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION && !call.cancel->cancelled()) {
      // A worker that cannot fetch the job's files (no --scheduler): once more, files inline.
      for (const v1::AssetRef& ref : spec.assets()) {
        v1::InlineAsset& asset = *request.add_assets();
        asset.set_sha256(ref.sha256());
        asset.set_data(read_whole_file(assets_.path_of(ref.sha256()), "asset"));
      }
      result = RenderedTiles();
      status = w.worker->render(request, result, deadline, *call.cancel);
    }
    return status;
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
}

// ---- Results -------------------------------------------------------------------------------------

void Dispatcher::handle_result(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                               RenderedTiles& result) {
  CancelReason reason;
  std::string reason_text;
  {
    std::lock_guard lock(mutex_);
    reason = call.reason;
    reason_text = call.reason_text;
  }
  if (reason == CancelReason::JobCancelled) return;  // the job is final; its tiles stay as they were
  if (status.ok()) {
    keep(w, call.batch, result);
  } else if (reason == CancelReason::Stopping) {
    store_.batch_requeue(call.batch.job_id, call.batch.first, call.batch.count);
  } else {
    failed(w, call, status, reason, reason_text);
  }
}

void Dispatcher::keep(const WorkerEntry& w, const TileBatch& batch, RenderedTiles& result) {
  const v1::TileStats& stats = result.response.stats();
  try {
    // The data first, then the mark: a done tile always has its data.
    assembly_.add(batch.job_id, jobs_.get(batch.job_id)->frame(), batch.first, result);
    if (!store_.batch_done(batch.job_id, batch.first, batch.count, stats)) return;
    measured(batch, stats);
    events_.publish(batch.job_id, [&](v1::JobEvent& event) {
      v1::TileFinished& f = *event.mutable_tile_finished();
      f.set_tile_index(batch.first);
      f.set_tile_count(batch.count);
      *f.mutable_rect() = to_proto(batch.rect);
      f.set_worker(w.worker->describe());
      *f.mutable_stats() = stats;
    });
    finisher_.finish_if_complete(batch.job_id);
  } catch (const std::exception& e) {
    log_.error("job {} {}: keeping the result: {}", batch.job_id, describe(batch), e.what());
    store_.batch_requeue(batch.job_id, batch.first, batch.count);
    work_.notify_all();
  }
}

void Dispatcher::measured(const TileBatch& batch, const v1::TileStats& stats) {
  // What a tile costs a worker running at full speed: its threads' CPU time shared by them. The
  // call's wall time would also count the time its threads waited for a core (two workers on
  // one machine, or two calls in flight on one worker), and halve the batches for nothing.
  const double per_call = stats.cpu_ms() > 0 && stats.threads() > 0 ? stats.cpu_ms() / stats.threads()
                                                                      : stats.render_ms();
  jobs_.add_tile_cost(batch.job_id, per_call / std::max<std::uint32_t>(1, batch.count));
}

void Dispatcher::failed(WorkerEntry& w, const InFlight& call, const grpc::Status& status,
                        CancelReason reason, const std::string& reason_text) {
  const TileBatch& batch = call.batch;
  const std::string worker = w.worker->describe();
  std::string why;
  int max_attempts = options_.max_attempts;
  if (reason == CancelReason::WorkerLeft) {
    why = fmt::format("worker {} left: {}", worker, reason_text);
  } else if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) {
    why = fmt::format("worker {}: no result within the tile deadline of {} ms{}", worker,
                      options_.tile_deadline.count(),
                      batch.count > 1 ? fmt::format(" (x {} tiles)", batch.count) : std::string());
    // Slow or hung? It gets no more tiles until it answers a health check: a hung one would
    // otherwise take tile after tile to its deadline.
    workers_.mark_down(w, std::chrono::milliseconds(0));
  } else {
    why = fmt::format("worker {}: {}: {}", worker, status_code_name(status.error_code()), status.error_message());
    // A job every worker must refuse: retrying only wastes the farm's time.
    if (status.error_code() == grpc::StatusCode::INVALID_ARGUMENT) max_attempts = 1;
    if (status.error_code() == grpc::StatusCode::UNAVAILABLE) workers_.mark_down(w, options_.probe_interval);
  }
  log_.warn("job {} {}: {}", batch.job_id, describe(batch), why);
  const v1::JobState before = store_.get_job(batch.job_id)->state();
  const TileFailure failure =
      store_.batch_failed(batch.job_id, batch.first, batch.count, why, max_attempts, unix_ms_now());
  events_.publish(batch.job_id, [&](v1::JobEvent& event) {
    v1::TileFailed& f = *event.mutable_tile_failed();
    f.set_tile_index(batch.first);
    f.set_tile_count(batch.count);
    f.set_worker(worker);
    f.set_reason(why);
    f.set_will_retry(failure.will_retry);
  });
  if (failure.job.state() == v1::JOB_STATE_FAILED && before != v1::JOB_STATE_FAILED) {
    log_.error("job {} failed: {}", batch.job_id, failure.job.failure_reason());
    {
      // Its other tiles in flight are of no use now.
      std::lock_guard lock(mutex_);
      cancel_calls_locked([&](const InFlight& other) { return other.batch.job_id == batch.job_id && &other != &call; },
                          CancelReason::JobCancelled);
    }
    events_.publish_state(failure.job, before);
    finisher_.release(batch.job_id);
  }
  work_.notify_all();
}

}  // namespace farm
