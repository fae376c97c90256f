#include "server/scheduler/scheduler_core.h"

#include <fmt/format.h>

#include <random>

#include "renderer/geometry/accel_validation.h"
#include "renderer/prepared_scene.h"
#include "renderer/render_frame.h"
#include "renderer/scene/input_error.h"
#include "renderer/scene/scene_builder.h"
#include "server/common/read_whole_file.h"
#include "server/common/scene_hash.h"
#include "server/common/scene_materializer.h"
#include "server/common/service_error.h"
#include "server/scheduler/job_merger.h"

namespace farm {

namespace fs = std::filesystem;
using SteadyClock = std::chrono::steady_clock;

namespace {

// Why a call in flight was cancelled by the scheduler, which decides what becomes of its tile.
enum class CancelReason { None, JobCancelled, WorkerLeft, Stopping };

std::string new_job_id() {
  static std::mutex mutex;
  static std::mt19937_64 random{std::random_device{}()};
  std::lock_guard lock(mutex);
  return fmt::format("{:016x}", random());
}

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  if (from.empty()) return;
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
}

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

}  // namespace

struct SchedulerCore::InFlight {
  TileBatch batch;
  std::string worker_id;
  std::shared_ptr<TileCancel> cancel = std::make_shared<TileCancel>();
  CancelReason reason = CancelReason::None;  // under SchedulerCore::mutex_
  std::string reason_text;
};

struct SchedulerCore::WorkerEntry {
  std::string id;
  std::shared_ptr<TileWorker> worker;
  bool registered = false;
  // Under SchedulerCore::mutex_:
  bool removed = false;
  bool down = true;  // probed before the first tile
  // A worker that just failed is left alone this long before it is probed: its channel may
  // still look connected for a moment after the process died.
  SteadyClock::time_point probe_after = SteadyClock::now();
  SteadyClock::time_point last_heartbeat = SteadyClock::now();
};

struct SchedulerCore::JobInfo {
  std::shared_ptr<const v1::JobSpec> spec;
  std::string scene_hash;
  std::shared_ptr<const Job> job;
  FrameLayout frame;
  std::shared_ptr<const PreparedScene> scene;  // null: the merge builds one if it needs it
  MergedFiles files;                            // empty: results/<job id>/<stem>.exr and .png
  std::function<void(TileBuffer&&)> merged;
};

bool JobEventQueue::pop(v1::JobEvent& event, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [&] { return !events_.empty(); })) return false;
  event = std::move(events_.front());
  events_.pop_front();
  return true;
}

void JobEventQueue::push(const v1::JobEvent& event) {
  {
    std::lock_guard lock(mutex_);
    events_.push_back(event);
  }
  ready_.notify_all();
}

SchedulerCore::SchedulerCore(SchedulerOptions options)
    : options_(std::move(options)),
      assets_((fs::create_directories(options_.data_dir), options_.data_dir / "assets")),
      store_(options_.in_memory ? fs::path(":memory:") : options_.data_dir / "jobs.db"),
      log_(make_logger("scheduler", options_.log_level)) {
  if (options_.in_memory) {
    assembly_ = std::make_unique<InMemoryAssembly>();
  } else {
    assembly_ = std::make_unique<TileFileAssembly>(options_.data_dir / "tiles");
  }
  // Jobs interrupted between their last tile and their merge.
  for (const std::string& id : store_.active_jobs()) finish_if_complete(id);
  threads_.emplace_back([this] { monitor_loop(); });
}

SchedulerCore::~SchedulerCore() { stop(); }

void SchedulerCore::stop() {
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
    for (const auto& call : in_flight_) {
      call->reason = CancelReason::Stopping;
      call->cancel->cancel();
    }
    threads.swap(threads_);
  }
  work_.notify_all();
  for (std::thread& t : threads) t.join();
}

// ---- Jobs ----------------------------------------------------------------------------------------

v1::Job SchedulerCore::submit(const v1::JobSpec& spec, int priority,
                              const std::shared_ptr<JobEventQueue>& watcher) {
  validate_asset_refs(spec);
  if (auto missing = missing_assets(spec, assets_); !missing.empty()) {
    throw ServiceError(grpc::StatusCode::FAILED_PRECONDITION,
                       fmt::format("{} on the scheduler (upload with UploadAsset first)",
                                   MissingAssetsError(missing).what()));
  }
  const std::string hash = scene_hash(spec);
  MaterializedScene m = materialize_scene(spec, hash, assets_, options_.data_dir);
  Scene scene;
  try {
    // What `farm render` does before rendering: models load, the scene builds.
    scene = build_scene(m.job);
  } catch (const InputError& e) {
    std::string message = e.what();
    replace_all(message, m.dir.string() + "/", "");
    replace_all(message, m.dir.string(), "the job's folder");
    throw InputError(message);
  }
  auto info = std::make_shared<JobInfo>();
  if (options_.validated_scene) {
    options_.validated_scene(hash, m.job, std::move(scene));
  } else if (m.job.embree_rays > 0) {
    info->scene = std::make_shared<const PreparedScene>(std::move(scene));  // for the merge's check
  }
  info->spec = std::make_shared<const v1::JobSpec>(spec);
  info->scene_hash = hash;
  info->job = std::make_shared<const Job>(std::move(m.job));
  return queue_job(priority, watcher, std::move(info));
}

v1::Job SchedulerCore::submit_validated(ValidatedJob job, int priority,
                                        const std::shared_ptr<JobEventQueue>& watcher) {
  if (!job.job || job.exr.empty()) throw std::invalid_argument("submit_validated: no job or no EXR path");
  auto info = std::make_shared<JobInfo>();
  info->spec = std::make_shared<const v1::JobSpec>(std::move(job.spec));
  info->scene_hash = std::move(job.scene_hash);
  info->job = std::move(job.job);
  info->scene = std::move(job.scene);
  info->files = {std::move(job.exr), std::move(job.preview)};
  info->merged = std::move(job.merged);
  return queue_job(priority, watcher, std::move(info));
}

v1::Job SchedulerCore::queue_job(int priority, const std::shared_ptr<JobEventQueue>& watcher,
                                 std::shared_ptr<JobInfo> info) {
  const RenderSettings& r = info->job->render;
  info->frame = {Rect{0, 0, r.width, r.height}, r.aovs};
  NewJob job;
  job.id = new_job_id();
  job.name = info->job->name;
  job.spec = *info->spec;
  job.scene_hash = info->scene_hash;
  job.engine = to_string(r.engine);
  job.width = r.width;
  job.height = r.height;
  job.priority = priority;
  job.tiles = split_into_tiles(r.width, r.height, r.tile_size);
  if (watcher) {
    std::lock_guard lock(watch_mutex_);
    watchers_.emplace(job.id, watcher);
  }
  {
    std::lock_guard lock(mutex_);
    jobs_.emplace(job.id, std::move(info));
  }
  v1::Job added = store_.add_job(job, unix_ms_now());
  log_->info("job {} '{}' queued: {} {}x{}, {} tiles, priority {}", added.job_id(), added.name(),
               added.engine(), added.width(), added.height(), added.tiles_total(), priority);
  work_.notify_all();
  return added;
}

std::optional<v1::Job> SchedulerCore::get_job(const std::string& job_id) const {
  return store_.get_job(job_id);
}

v1::Job SchedulerCore::cancel(const std::string& job_id) {
  std::optional<v1::Job> before = store_.get_job(job_id);
  if (!before) throw ServiceError(grpc::StatusCode::NOT_FOUND, "no job '" + job_id + "'");
  v1::Job after;
  {
    // Under the dispatcher's lock, so no slot claims a tile of this job and starts it unseen.
    std::lock_guard lock(mutex_);
    after = store_.cancel_job(job_id, unix_ms_now());
    for (const auto& call : in_flight_) {
      if (call->batch.job_id == job_id) {
        call->reason = CancelReason::JobCancelled;
        call->cancel->cancel();
      }
    }
  }
  if (after.state() != before->state()) {
    log_->info("job {} cancelled", job_id);
    publish_state(after, before->state());
    cleanup_job_files(job_id);
  }
  return after;
}

std::optional<fs::path> SchedulerCore::result_file(const std::string& job_id, bool preview) const {
  const std::optional<v1::Job> job = store_.get_job(job_id);
  if (!job || job->state() != v1::JOB_STATE_SUCCEEDED) return std::nullopt;
  const fs::path dir = options_.data_dir / "results" / job_id;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with(".")) continue;
    if (e.path().extension() == (preview ? ".png" : ".exr")) return e.path();
  }
  return std::nullopt;
}

std::shared_ptr<const SchedulerCore::JobInfo> SchedulerCore::job_info(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    if (auto it = jobs_.find(job_id); it != jobs_.end()) return it->second;
  }
  // A job an earlier process queued: its spec from the store, laid out and parsed once.
  std::optional<v1::Job> job = store_.get_job(job_id);
  std::optional<v1::JobSpec> spec = store_.get_spec(job_id);
  if (!job || !spec) throw std::runtime_error("no spec for job " + job_id);
  auto info = std::make_shared<JobInfo>();
  info->spec = std::make_shared<const v1::JobSpec>(std::move(*spec));
  info->scene_hash = job->scene_hash();
  info->job = std::make_shared<const Job>(
      materialize_scene(*info->spec, info->scene_hash, assets_, options_.data_dir).job);
  const RenderSettings& r = info->job->render;
  info->frame = {Rect{0, 0, r.width, r.height}, r.aovs};
  std::lock_guard lock(mutex_);
  return jobs_.emplace(job_id, std::move(info)).first->second;
}

// ---- Events --------------------------------------------------------------------------------------

std::shared_ptr<JobEventQueue> SchedulerCore::watch(const std::string& job_id) {
  auto queue = std::make_shared<JobEventQueue>();
  std::lock_guard lock(watch_mutex_);
  watchers_.emplace(job_id, queue);
  return queue;
}

void SchedulerCore::unwatch(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue) {
  std::lock_guard lock(watch_mutex_);
  auto [begin, end] = watchers_.equal_range(job_id);
  for (auto it = begin; it != end; ++it) {
    if (it->second == queue) {
      watchers_.erase(it);
      return;
    }
  }
}

void SchedulerCore::publish(const v1::JobEvent& event) {
  std::lock_guard lock(watch_mutex_);
  auto [begin, end] = watchers_.equal_range(event.job().job_id());
  for (auto it = begin; it != end; ++it) it->second->push(event);
}

void SchedulerCore::publish_with_job(const std::string& job_id,
                                     const std::function<void(v1::JobEvent&)>& fill) {
  // The job is read under the watchers' lock, so that events from concurrent slots reach a
  // watcher in the order of the store's changes: tiles_done never goes back.
  std::lock_guard lock(watch_mutex_);
  v1::JobEvent event;
  *event.mutable_job() = *store_.get_job(job_id);
  fill(event);
  auto [begin, end] = watchers_.equal_range(job_id);
  for (auto it = begin; it != end; ++it) it->second->push(event);
}

void SchedulerCore::publish_state(const v1::Job& job, v1::JobState from) {
  v1::JobEvent event;
  *event.mutable_job() = job;
  event.mutable_state_changed()->set_from(from);
  event.mutable_state_changed()->set_to(job.state());
  publish(event);
}

void SchedulerCore::cleanup_job_files(const std::string& job_id) {
  assembly_->remove_job(job_id);
  std::lock_guard lock(mutex_);
  jobs_.erase(job_id);
  ms_per_tile_.erase(job_id);
}

// ---- Workers -------------------------------------------------------------------------------------

std::string SchedulerCore::add_worker(std::shared_ptr<TileWorker> worker, bool registered) {
  auto entry = std::make_shared<WorkerEntry>();
  entry->worker = std::move(worker);
  entry->registered = registered;
  std::lock_guard lock(mutex_);
  entry->id = fmt::format("w{}-{}", ++next_worker_, entry->worker->describe());
  workers_.emplace(entry->id, entry);
  if (!stopping_) {
    for (int i = 0; i < std::max(1, options_.tiles_per_worker); ++i) {
      threads_.emplace_back([this, entry] { slot_loop(entry); });
    }
  }
  log_->info("worker {} added{}", entry->id, registered ? " (registered)" : "");
  return entry->id;
}

void SchedulerCore::remove_worker(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end()) return;
    it->second->removed = true;
    for (const auto& call : in_flight_) {
      if (call->worker_id == worker_id) {
        call->reason = CancelReason::WorkerLeft;
        call->reason_text = reason;
        call->cancel->cancel();
      }
    }
    workers_.erase(it);
  }
  log_->warn("worker {} removed: {}", worker_id, reason);
  work_.notify_all();
}

bool SchedulerCore::heartbeat(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  auto it = workers_.find(worker_id);
  if (it == workers_.end()) return false;
  it->second->last_heartbeat = SteadyClock::now();
  return true;
}

std::size_t SchedulerCore::worker_count() const {
  std::lock_guard lock(mutex_);
  return workers_.size();
}

void SchedulerCore::monitor_loop() {
  const auto limit = options_.heartbeat_interval * options_.missed_heartbeats;
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    work_.wait_for(lock, options_.heartbeat_interval / 2);
    std::vector<std::string> silent;
    for (const auto& [id, w] : workers_) {
      if (w->registered && SteadyClock::now() - w->last_heartbeat > limit) silent.push_back(id);
    }
    lock.unlock();
    for (const std::string& id : silent) {
      remove_worker(id, fmt::format("no heartbeat for {} ms", limit.count()));
    }
    lock.lock();
  }
}

// ---- Dispatch ------------------------------------------------------------------------------------

void SchedulerCore::slot_loop(const std::shared_ptr<WorkerEntry>& w) {
  std::unique_lock lock(mutex_);
  while (!stopping_ && !w->removed) {
    if (w->down) {
      if (SteadyClock::now() < w->probe_after) {
        work_.wait_until(lock, w->probe_after, [&] { return stopping_ || w->removed; });
        continue;
      }
      lock.unlock();
      const bool up = w->worker->probe(options_.probe_interval);
      lock.lock();
      if (!up) {
        work_.wait_for(lock, options_.probe_interval / 4, [&] { return stopping_ || w->removed; });
        continue;
      }
      if (w->down) log_->info("worker {} is up", w->id);
      w->down = false;
      continue;
    }
    std::optional<TileBatch> batch;
    try {
      batch = store_.claim_next_batch(w->id, unix_ms_now(), [this](const std::string& job_id, int queued) {
        return batch_size_locked(job_id, queued);
      });
    } catch (const std::exception& e) {
      log_->error("claiming tiles: {}", e.what());
    }
    if (!batch) {
      work_.wait_for(lock, std::chrono::milliseconds(500));
      continue;
    }
    auto call = std::make_shared<InFlight>();
    call->batch = *batch;
    call->worker_id = w->id;
    in_flight_.insert(call);
    lock.unlock();

    v1::RenderTileRequest request;
    RenderedTiles result;
    grpc::Status status;
    try {
      const std::shared_ptr<const JobInfo> info = job_info(batch->job_id);
      const v1::JobSpec& spec = *info->spec;
      *request.mutable_job() = spec;
      request.set_scene_hash(info->scene_hash);
      *request.mutable_rect() = to_proto(batch->rect);
      request.set_job_id(batch->job_id);
      request.set_tile_index(batch->first);
      // Each tile of the batch has its deadline.
      const auto deadline = std::chrono::system_clock::now() + options_.tile_deadline * batch->count;
      status = w->worker->render(request, result, deadline, *call->cancel);
      if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION && !call->cancel->cancelled()) {
        // A worker that cannot fetch the job's files (no --scheduler): once more, files inline.
        for (const v1::AssetRef& ref : spec.assets()) {
          v1::InlineAsset& asset = *request.add_assets();
          asset.set_sha256(ref.sha256());
          asset.set_data(read_whole_file(assets_.path_of(ref.sha256()), "asset"));
        }
        result = RenderedTiles();
        status = w->worker->render(request, result, deadline, *call->cancel);
      }
    } catch (const std::exception& e) {
      status = grpc::Status(grpc::StatusCode::INTERNAL, e.what());
    }
    handle_result(w, *call, status, result);

    lock.lock();
    in_flight_.erase(call);
  }
}

int SchedulerCore::batch_size_locked(const std::string& job_id, int queued_tiles) const {
  if (options_.batch_target.count() <= 0) return 1;
  const auto it = ms_per_tile_.find(job_id);
  if (it == ms_per_tile_.end()) return 1;  // nothing measured yet: the first tiles tell
  int slots = 0;
  for (const auto& [id, w] : workers_) slots += w->down ? 0 : std::max(1, options_.tiles_per_worker);
  // The tail goes out in small pieces, so that no worker is left with a long batch while the
  // others have nothing: at most half of each slot's share of what is queued.
  const int share = queued_tiles / (2 * std::max(1, slots));
  const double by_time = static_cast<double>(options_.batch_target.count()) / std::max(it->second, 1e-3);
  return std::clamp(std::min(static_cast<int>(by_time), share), 1, kMaxBatch);
}

void SchedulerCore::measured(const TileBatch& batch, const v1::TileStats& stats) {
  // What a tile costs a worker running at full speed: its threads' CPU time shared by them. The
  // call's wall time would also count the time its threads waited for a core (two workers on
  // one machine, or two calls in flight on one worker), and halve the batches for nothing.
  const double per_call = stats.cpu_ms() > 0 && stats.threads() > 0 ? stats.cpu_ms() / stats.threads()
                                                                      : stats.render_ms();
  const double ms = per_call / std::max<std::uint32_t>(1, batch.count);
  std::lock_guard lock(mutex_);
  auto [it, added] = ms_per_tile_.emplace(batch.job_id, ms);
  if (!added) it->second = 0.5 * (it->second + ms);  // tiles differ: follow the recent ones
}

void SchedulerCore::handle_result(const std::shared_ptr<WorkerEntry>& w, const InFlight& call,
                                  const grpc::Status& status, RenderedTiles& result) {
  const v1::RenderTileResponse& response = result.response;
  const TileBatch& batch = call.batch;
  CancelReason reason;
  std::string reason_text;
  {
    std::lock_guard lock(mutex_);
    reason = call.reason;
    reason_text = call.reason_text;
  }
  if (status.ok() && reason != CancelReason::JobCancelled) {
    try {
      // The data first, then the mark: a done tile always has its data.
      assembly_->add(batch.job_id, job_info(batch.job_id)->frame, batch.first, result);
      if (store_.batch_done(batch.job_id, batch.first, batch.count, response.stats())) {
        measured(batch, response.stats());
        publish_with_job(batch.job_id, [&](v1::JobEvent& event) {
          v1::TileFinished& f = *event.mutable_tile_finished();
          f.set_tile_index(batch.first);
          f.set_tile_count(batch.count);
          *f.mutable_rect() = to_proto(batch.rect);
          f.set_worker(w->worker->describe());
          *f.mutable_stats() = response.stats();
        });
        finish_if_complete(batch.job_id);
      }
      return;
    } catch (const std::exception& e) {
      log_->error("job {} {}: keeping the result: {}", batch.job_id, describe(batch), e.what());
      store_.batch_requeue(batch.job_id, batch.first, batch.count);
      work_.notify_all();
      return;
    }
  }
  if (reason == CancelReason::JobCancelled) return;  // the job is final; its tiles stay as they were
  if (reason == CancelReason::Stopping) {
    store_.batch_requeue(batch.job_id, batch.first, batch.count);
    return;
  }

  std::string why;
  int max_attempts = options_.max_attempts;
  if (reason == CancelReason::WorkerLeft) {
    why = fmt::format("worker {} left: {}", w->worker->describe(), reason_text);
  } else {
    why = fmt::format("worker {}: {}: {}", w->worker->describe(), status_code_name(status.error_code()),
                      status.error_message());
    if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) {
      why = fmt::format("worker {}: no result within the tile deadline of {} ms{}",
                        w->worker->describe(), options_.tile_deadline.count(),
                        batch.count > 1 ? fmt::format(" (x {} tiles)", batch.count) : std::string());
      // Slow or hung? It gets no more tiles until it answers a health check: a hung one would
      // otherwise take tile after tile to its deadline.
      std::lock_guard lock(mutex_);
      w->down = true;
      w->probe_after = SteadyClock::now();
    }
    // A job every worker must refuse: retrying only wastes the farm's time.
    if (status.error_code() == grpc::StatusCode::INVALID_ARGUMENT) max_attempts = 1;
    if (status.error_code() == grpc::StatusCode::UNAVAILABLE) {
      std::lock_guard lock(mutex_);
      w->down = true;
      w->probe_after = SteadyClock::now() + options_.probe_interval;
    }
  }
  log_->warn("job {} {}: {}", batch.job_id, describe(batch), why);
  const v1::JobState before = store_.get_job(batch.job_id)->state();
  const TileFailure failure =
      store_.batch_failed(batch.job_id, batch.first, batch.count, why, max_attempts, unix_ms_now());
  publish_with_job(batch.job_id, [&](v1::JobEvent& event) {
    v1::TileFailed& f = *event.mutable_tile_failed();
    f.set_tile_index(batch.first);
    f.set_tile_count(batch.count);
    f.set_worker(w->worker->describe());
    f.set_reason(why);
    f.set_will_retry(failure.will_retry);
  });
  if (failure.job.state() == v1::JOB_STATE_FAILED && before != v1::JOB_STATE_FAILED) {
    log_->error("job {} failed: {}", batch.job_id, failure.job.failure_reason());
    {
      // Its other tiles in flight are of no use now.
      std::lock_guard lock(mutex_);
      for (const auto& other : in_flight_) {
        if (other->batch.job_id == batch.job_id && other.get() != &call) {
          other->reason = CancelReason::JobCancelled;
          other->cancel->cancel();
        }
      }
    }
    publish_state(failure.job, before);
    cleanup_job_files(batch.job_id);
  }
  work_.notify_all();
}

void SchedulerCore::finish_if_complete(const std::string& job_id) {
  const std::optional<v1::Job> job = store_.get_job(job_id);
  if (!job || is_final(job->state()) || job->tiles_done() < job->tiles_total()) return;
  {
    std::lock_guard lock(mutex_);
    if (!merging_.insert(job_id).second) return;
  }
  merge(job_id);
  std::lock_guard lock(mutex_);
  merging_.erase(job_id);
}

void SchedulerCore::merge(const std::string& job_id) {
  const v1::Job before = *store_.get_job(job_id);
  v1::Job after;
  try {
    const std::shared_ptr<const JobInfo> info = job_info(job_id);
    const Job& job = *info->job;
    std::set<std::uint32_t> parts;
    for (const TileRecord& t : store_.tiles(job_id)) parts.insert(t.part);
    TileBuffer film = assembly_->assemble(job_id, info->frame, {parts.begin(), parts.end()});
    MergedFiles files = info->files;
    if (files.exr.empty()) {
      std::string stem = job.output.image.stem().string();
      if (stem.empty() || stem.starts_with(".")) stem = "image";
      const fs::path dir = options_.data_dir / "results" / job_id;
      files = {dir / (stem + ".exr"), dir / (stem + ".png")};
    }
    write_merged(film, files, options_.exr_type);

    std::string validation;
    if (job.embree_rays > 0) {
      // The scene the job was rendered from when this process built it; else built here.
      std::shared_ptr<const PreparedScene> scene = info->scene;
      if (!scene) scene = std::make_shared<const PreparedScene>(build_scene(job));
      const AccelKind accel = accel_to_validate(job.render.accel);
      const AccelValidation v = validate_against_embree(
          *scene, job.render, accel, static_cast<std::uint64_t>(job.embree_rays));
      validation = fmt::format("{} ({} vs embree{})", v.summary(), to_string(accel),
                               validation_passes(v) ? "" : "; more hit/miss disagreements than 0.001% of rays");
    }
    if (info->merged) info->merged(std::move(film));
    after = store_.finish_job(job_id, v1::JOB_STATE_SUCCEEDED, "", validation, unix_ms_now());
    log_->info("job {} done: {} tiles merged from {} calls", job_id, before.tiles_total(),
             parts.size());
  } catch (const std::exception& e) {
    after = store_.finish_job(job_id, v1::JOB_STATE_FAILED,
                              fmt::format("merging the tiles: {}", e.what()), "", unix_ms_now());
    log_->error("job {} failed: {}", job_id, after.failure_reason());
  }
  if (after.state() != before.state()) publish_state(after, before.state());
  cleanup_job_files(job_id);
}

}  // namespace farm
