#include "server/scheduler/scheduler_core.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>
#include <random>

#include "renderer/render_frame.h"
#include "server/common/job_state.h"
#include "server/common/service_error.h"
#include "server/scheduler/jobs/unit_grid.h"
#include "server/scheduler/workers/placement.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

std::string new_job_id() {
  static std::mutex mutex;
  static std::mt19937_64 random{std::random_device{}()};
  std::lock_guard lock(mutex);
  return fmt::format("{:016x}", random());
}

std::string describe_state(const v1::Job& job) {
  return fmt::format("job {} is {}", job.job_id(), to_string(job.state()));
}

// A dependency the store refused, as the caller is told: a job that has started is the job's
// state, anything else (no such job, too many, a cycle) the request's.
[[noreturn]] void refuse(const DependencyError& e) {
  throw ServiceError(e.kind == DependencyError::Kind::Started ? grpc::StatusCode::FAILED_PRECONDITION
                                                              : grpc::StatusCode::INVALID_ARGUMENT,
                     e.what());
}

[[noreturn]] void no_job(const std::string& job_id) {
  throw ServiceError(grpc::StatusCode::NOT_FOUND, fmt::format("no job '{}'", job_id));
}

std::unique_ptr<FrameAssembly> make_assembly(const SchedulerOptions& options) {
  if (options.in_memory) return std::make_unique<InMemoryAssembly>();
  return std::make_unique<TileFileAssembly>(options.data_dir / "tiles");
}

}  // namespace

SchedulerCore::SchedulerCore(SchedulerOptions options)
    : options_(std::move(options)),
      assets_((fs::create_directories(options_.data_dir), options_.data_dir / "assets")),
      asset_quota_(assets_.dir(), options_.limits.max_asset_store_bytes),
      store_(connect_store(options_.in_memory    ? std::string(":memory:")
                           : options_.store.empty() ? (options_.data_dir / "jobs.db").string()
                                                    : options_.store)),
      log_(make_logger("scheduler", options_.log_level)),
      assembly_(make_assembly(options_)),
      specs_(options_, assets_),
      jobs_(store_, assets_, options_.data_dir),
      events_(store_),
      pause_(*log_, options_.disk_full_backoff, options_.disk_full_backoff_max),
      outage_(*log_),
      results_(options_.data_dir, store_, *assembly_, jobs_),
      finisher_(options_, store_, *assembly_, jobs_, results_, events_, pause_, outage_, *log_),
      workers_(
          options_, *log_, [this](const std::string& id, const std::string& reason) { remove_worker(id, reason); },
          [this](const std::shared_ptr<WorkerEntry>& w) { dispatcher_.start_slots(w); }),
      dispatcher_(options_, {.store = store_,
                             .assets = assets_,
                             .assembly = *assembly_,
                             .jobs = jobs_,
                             .events = events_,
                             .workers = workers_,
                             .finisher = finisher_,
                             .pause = pause_,
                             .outage = outage_,
                             .log = *log_}) {
  // A scheduler killed mid-upload left the upload's temporary file: not counted, never published.
  if (const std::size_t swept = assets_.sweep_abandoned_uploads()) {
    log_->info("removed {} upload(s) cut short from {}", swept, assets_.dir().string());
  }
  // Room on the disk again: the merges the disk refused first (they free their tiles), then
  // the slots. Still none: the youngest job holding tiles gives them back.
  pause_.on_resume([this] {
    finisher_.retry_refused();
    dispatcher_.work_queued();
  });
  pause_.on_still_full([this] { return finisher_.make_room(); });
  // A merge that found damaged tile results queued their tiles again: the slots take them now.
  finisher_.on_requeued([this] { dispatcher_.work_queued(); });
  // The store's server back after an outage: the merges and ends it interrupted, then the slots.
  outage_.on_back([this] {
    finish_active_jobs();
    dispatcher_.work_queued();
  });
  // On a store several schedulers share, this one's units are marked with its id and held under a
  // lease; the units of one that died come back when its lease runs out.
  store_.leases().set_scheduler(scheduler_id_);
  if (store_.is_shared()) {
    // A scheduler reaped: its units are queued again for the slots, and the merges and ends it
    // had claimed are free for this one.
    lease_ = std::make_unique<SchedulerLease>(store_, outage_, *log_, options_.lease, [this] {
      dispatcher_.work_queued();
      finish_active_jobs();
    });
    // A job another scheduler ended: its units in flight here stop, and its memory here goes.
    relay_ = std::make_unique<EventRelay>(options_.store, events_, *log_, [this](const v1::JobEvent& event) {
      if (!event.has_state_changed() || !is_final(event.state_changed().to())) return;
      if (event.state_changed().to() != v1::JOB_STATE_SUCCEEDED) {
        log_->info("job {} {} on another scheduler: its units in flight here stopped", event.job().job_id(),
                   v1::JobState_Name(event.state_changed().to()));
      }
      dispatcher_.job_ended_elsewhere(event.job().job_id());
      if (release_) release_->wake();
      finisher_.release(event.job().job_id(), event.state_changed().to() != v1::JOB_STATE_SUCCEEDED);
    });
  }
  // Jobs interrupted between their last tile and their merge.
  finish_active_jobs();
  // Jobs waiting for others: looked at when a job ends here, and every second for the ends of
  // other schedulers' jobs. A merged frame may free a job following it frame by frame.
  release_ = std::make_unique<DependencyRelease>(store_, *log_, options_.dependency_sweep,
                                                 [this](const std::vector<ReleasedJob>& jobs) { settled(jobs); });
  events_.listen([this](const v1::JobEvent& event) {
    if (event.has_state_changed() && is_final(event.state_changed().to())) release_->wake();
    if (event.has_frame_finished()) dispatcher_.work_queued();
  });
  if (options_.keep_finished.count() > 0) {
    retention_ = std::make_unique<RetentionSweeper>(
        options_.keep_finished, *log_, [this](std::int64_t before_ms) { return remove_finished_before(before_ms); });
  }
}

std::string make_scheduler_id() {
  char host[256] = {};
  if (gethostname(host, sizeof host - 1) != 0) std::snprintf(host, sizeof host, "unknown");
  std::random_device random;
  return fmt::format("{}:{}:{:08x}", host, getpid(), random());
}

SchedulerCore::~SchedulerCore() { stop(); }

void SchedulerCore::finish_active_jobs() {
  for (const std::string& id : store_.jobs().active_jobs()) finisher_.finish_if_complete(id);
}

void SchedulerCore::stop() {
  // The registry first: slots waiting for a worker to come up return, and no worker is dropped
  // while the dispatcher cancels and joins.
  if (release_) release_->stop();  // first: it announces through the dispatcher and the finisher
  if (retention_) retention_->stop();  // likewise: it deletes through the finisher
  if (relay_) relay_->stop();  // its thread calls the dispatcher and the finisher
  workers_.stop();
  pause_.stop();
  dispatcher_.stop();
  finisher_.stop();  // after the slots: none hands it a job to end any more
  if (lease_) lease_->stop();  // after the dispatcher queued its running units again
}

// ---- Jobs ----------------------------------------------------------------------------------------

v1::Job SchedulerCore::submit(ValidatedJob validated, int priority, const std::shared_ptr<JobEventQueue>& watcher,
                              const std::string& owner, const QueueTerms& terms) {
  if (!validated.job) throw std::invalid_argument("SchedulerCore::submit: no job");
  auto info = std::make_shared<JobInfo>();
  info->spec = std::make_shared<const v1::JobSpec>(std::move(validated.spec));
  info->scene_hash = std::move(validated.scene_hash);
  info->job = std::move(validated.job);
  info->scene = std::move(validated.scene);
  info->files = {std::move(validated.exr), std::move(validated.preview)};
  info->video = std::move(validated.video);
  info->merged = std::move(validated.merged);
  const RenderSettings& r = info->job->render;
  NewJob job;
  job.id = new_job_id();
  job.name = info->job->name;
  job.spec = *info->spec;
  job.scene_hash = info->scene_hash;
  job.engine = to_string(r.engine);
  job.width = r.width;
  job.height = r.height;
  job.priority = priority;
  job.owner = owner;
  job.tiles = UnitGrid(r, options_.min_unit_edge).rects();
  job.frames = job_frames(*info->job);
  if (info->job->frames) job.frame_step = info->job->frames->step;
  job.passes = pass_count(r);
  job.requirements = info->job->requirements;
  job.caps = info->job->caps;
  if (terms.caps.max_workers > 0) job.caps.max_workers = terms.caps.max_workers;
  if (terms.caps.max_units_in_flight > 0) job.caps.max_units_in_flight = terms.caps.max_units_in_flight;
  job.after = terms.after;
  job.after_any = terms.after_any;
  job.after_frames = terms.after_frames;
  if (terms.owner_weight_milli) job.owner_weight_milli = *terms.owner_weight_milli;
  if (watcher) events_.subscribe(job.id, watcher);
  jobs_.add(job.id, std::move(info));
  // Not queued (a full store: DiskFull; a dependency that names no job): nothing of it is kept.
  const auto forget = [&] {
    jobs_.forget(job.id);
    if (watcher) events_.unsubscribe(job.id, watcher);
  };
  v1::Job added;
  try {
    added = store_.jobs().add_job(job, unix_ms_now());
  } catch (const DependencyError& e) {
    forget();
    refuse(e);
  } catch (...) {
    forget();
    throw;
  }
  store_.dependencies().describe(added);
  const std::string waits = describe_dependencies(added);
  log_->info("job {} '{}' {}: {} {}x{}, {} frame(s), {} units, priority {}{}{}", added.job_id(), added.name(),
             to_string(added.state()), added.engine(), added.width(), added.height(), added.frames_total(),
             added.tiles_total(), priority, owner.empty() ? "" : ", owner " + owner, waits.empty() ? "" : ", " + waits);
  events_.publish_state(added, v1::JOB_STATE_UNSPECIFIED);  // its first log entry: submitted
  if (added.state() == v1::JOB_STATE_WAITING) release_->wake();  // its dependencies may have ended
  dispatcher_.work_queued();
  return added;
}

std::optional<v1::Job> SchedulerCore::get_job(const std::string& job_id) const {
  std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (job) {
    explain_placement({&*job, 1});
    store_.dependencies().describe(*job);
  }
  return job;
}

void SchedulerCore::settled(const std::vector<ReleasedJob>& jobs) {
  bool queued = false;
  for (const ReleasedJob& r : jobs) {
    const v1::Job& job = r.job;
    if (job.state() == v1::JOB_STATE_FAILED) {
      log_->info("job {} failed: {}", job.job_id(), job.failure_reason());
      // One following another frame by frame may have units out: they stop, as a cancel's do.
      if (r.from != v1::JOB_STATE_WAITING) dispatcher_.job_ended_elsewhere(job.job_id());
      finisher_.release(job.job_id(), true);
    } else {
      log_->info("job {} queued: the jobs it waits for have ended", job.job_id());
      queued = true;
    }
    events_.publish_state(job, r.from);
  }
  if (queued) dispatcher_.work_queued();
}

void SchedulerCore::explain_placement(std::span<v1::Job> jobs) const {
  std::optional<std::vector<WorkerStatus>> known;
  for (v1::Job& job : jobs) {
    const WorkerRequirements needs = requirements_of(job);
    if (is_final(job.state()) || needs.empty()) continue;
    if (!known) known = workers();
    job.set_unplaceable(unplaceable_reason(needs, *known));
  }
}

v1::Job SchedulerCore::cancel(const std::string& job_id, const std::string& by) {
  std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  if (!before) no_job(job_id);
  const v1::Job after = dispatcher_.cancel_job(job_id);
  if (after.state() != before->state()) {
    log_->info("job {} cancelled{}", job_id, by.empty() ? "" : " by " + by);
    events_.publish_state(after, before->state(), by);
    finisher_.release(job_id, true);  // a retry renders what the cancel stopped, and keeps the rest
  }
  return after;
}

void SchedulerCore::announce(const std::string& job_id, const std::string& change, const std::string& by) {
  log_->info("job {} {}{}", job_id, change, by.empty() ? "" : " by " + by);
  events_.publish(job_id, [&](v1::JobEvent& e) {
    e.mutable_updated()->set_change(change);
    e.mutable_updated()->set_by(by);
  });
}

v1::Job SchedulerCore::pause(const std::string& job_id, bool paused, const std::string& by) {
  std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  if (!before) no_job(job_id);
  if (is_final(before->state())) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{}: only a queued or running job can be {}", describe_state(*before),
                                   paused ? "paused" : "resumed"));
  }
  const v1::Job after = *store_.jobs().set_paused(job_id, paused);
  if (after.paused() != before->paused()) {
    announce(job_id, paused ? "paused" : "resumed", by);
    if (!paused) dispatcher_.work_queued();
  }
  return after;
}

v1::Job SchedulerCore::set_priority(const std::string& job_id, int priority, const std::string& by) {
  std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  if (!before) no_job(job_id);
  const v1::Job after = *store_.jobs().set_priority(job_id, priority);
  if (after.priority() != before->priority()) {
    const std::string change = fmt::format("priority {} -> {}", before->priority(), after.priority());
    announce(job_id, change, by);
  }
  return after;
}

v1::Job SchedulerCore::set_caps(const std::string& job_id, std::optional<int> max_workers,
                                std::optional<int> max_units_in_flight, const std::string& by) {
  std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  if (!before) no_job(job_id);
  if (is_final(before->state())) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{}: only an unfinished job's caps can change", describe_state(*before)));
  }
  const v1::Job after = *store_.jobs().set_caps(job_id, max_workers, max_units_in_flight);
  const auto cap = [](std::uint32_t n) { return n == 0 ? std::string("none") : std::to_string(n); };
  std::string change;
  if (after.max_workers() != before->max_workers()) {
    change = fmt::format("max_workers {} -> {}", cap(before->max_workers()), cap(after.max_workers()));
  }
  if (after.max_units_in_flight() != before->max_units_in_flight()) {
    change += fmt::format("{}max_units_in_flight {} -> {}", change.empty() ? "" : ", ",
                          cap(before->max_units_in_flight()), cap(after.max_units_in_flight()));
  }
  if (!change.empty()) {
    announce(job_id, change, by);
    dispatcher_.work_queued();  // a cap raised or lifted lets more out now
  }
  return after;
}

v1::Job SchedulerCore::add_dependencies(const std::string& job_id, const std::vector<std::string>& after,
                                        const std::vector<std::string>& after_any, const std::string& by) {
  std::optional<v1::Job> job;
  try {
    job = store_.dependencies().add(job_id, after, after_any);
  } catch (const DependencyError& e) {
    refuse(e);
  }
  if (!job) no_job(job_id);
  store_.dependencies().describe(*job);
  announce(job_id, "waits: " + describe_dependencies(*job), by);
  release_->wake();
  return *job;
}

RetriedJob SchedulerCore::retry(const std::string& job_id, const std::string& by) {
  const std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  std::optional<RetriedJob> r = store_.jobs().retry_job(job_id);
  if (!r) no_job(job_id);
  if (!r->retried) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{}: only a failed or cancelled job can be retried", describe_state(r->job)));
  }
  const std::string change = fmt::format("retried: {} unit{} queued again, {} kept", r->units_queued,
                                         r->units_queued == 1 ? "" : "s", r->job.tiles_done());
  announce(job_id, change, by);
  events_.publish(job_id, [&](v1::JobEvent& e) {
    e.mutable_state_changed()->set_from(before ? before->state() : v1::JOB_STATE_FAILED);
    e.mutable_state_changed()->set_to(e.job().state());
  });
  // A job whose units were all done (it failed at its end: its check, its video) ends again now;
  // one with dependencies waits for them to settle it again.
  finisher_.finish_if_complete(job_id);
  if (r->job.state() == v1::JOB_STATE_WAITING) release_->wake();
  dispatcher_.work_queued();
  return *r;
}

std::uintmax_t SchedulerCore::remove(const std::string& job_id) {
  const std::optional<bool> deleted = store_.jobs().delete_job(job_id);
  if (!deleted) no_job(job_id);
  if (!*deleted) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{}: cancel it first (only a finished, failed or cancelled job is deleted)",
                                   describe_state(*store_.jobs().get_job(job_id))));
  }
  jobs_.forget(job_id);
  const std::uintmax_t bytes = finisher_.remove_files(job_id);
  log_->info("job {} deleted: {} bytes of files freed", job_id, bytes);
  return bytes;
}

std::size_t SchedulerCore::remove_finished_before(std::int64_t before_ms) {
  constexpr int kBatch = 100;  // jobs a pass; the next pass takes the rest
  std::size_t removed = 0;
  for (const std::string& id : store_.jobs().finished_before(before_ms, kBatch)) {
    try {
      remove(id);
      ++removed;
    } catch (const ServiceError&) {
      // Retried or deleted meanwhile (another scheduler of the store, an operator): nothing to do.
    }
  }
  return removed;
}

std::optional<fs::path> SchedulerCore::result_file(const std::string& job_id, bool preview,
                                                   std::optional<int> frame) const {
  return results_.result_file(job_id, preview, frame);
}

std::optional<fs::path> SchedulerCore::progressive_result(const std::string& job_id, int frame) const {
  return results_.progressive_result(job_id, frame);
}

std::optional<fs::path> SchedulerCore::live_preview(const std::string& job_id, int frame) {
  return results_.live_preview(job_id, frame);
}

std::optional<fs::path> SchedulerCore::video_file(const std::string& job_id) const {
  return results_.video_file(job_id);
}

// ---- Events --------------------------------------------------------------------------------------

std::shared_ptr<JobEventQueue> SchedulerCore::watch(const std::string& job_id, std::size_t capacity) {
  auto queue = std::make_shared<JobEventQueue>(capacity);
  events_.subscribe(job_id, queue);
  return queue;
}

SchedulerCore::WatchStart SchedulerCore::watch_from_now(const std::string& job_id, std::size_t capacity) {
  WatchStart start{std::make_shared<JobEventQueue>(capacity), std::nullopt};
  start.job = events_.subscribe_and_read(job_id, start.queue);
  return start;
}

void SchedulerCore::unwatch(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue) {
  events_.unsubscribe(job_id, queue);
}

// ---- Workers -------------------------------------------------------------------------------------

std::string SchedulerCore::add_worker(std::shared_ptr<TileWorker> worker, bool registered, WorkerFacts facts) {
  // Its slots start once the registry's prober finds it up: a worker that never answers costs
  // no threads.
  return workers_.add(std::move(worker), registered, std::move(facts))->id;
}

void SchedulerCore::remove_worker(const std::string& worker_id, const std::string& reason) {
  if (workers_.remove(worker_id, reason)) dispatcher_.worker_left(worker_id, reason);
}

bool SchedulerCore::heartbeat(const std::string& worker_id) { return workers_.heartbeat(worker_id); }

std::size_t SchedulerCore::worker_count() const { return workers_.count(); }

std::vector<WorkerStatus> SchedulerCore::workers() const { return workers_.workers(); }

std::vector<v1::WorkerInfo> SchedulerCore::worker_infos() const {
  return farm::worker_infos(workers_, {dispatcher_.calls_in_flight(),
                                       [this](const std::string& id) { return dispatcher_.blocked_jobs(id); }});
}

}  // namespace farm
