#pragma once
// The scheduler without its gRPC plumbing: jobs in (validated), tiles out to workers, tiles back,
// frames merged. `farm scheduler` serves it to its callers through its authorised front door
// (SchedulerFrontDoor, front_door.h), over gRPC and HTTP; `farm render` runs it in-process with one
// InProcessTileWorker (EmbeddedFarm), its only caller the process itself. One pipeline, two front
// ends. The core checks no roles: who may call it is the front door's to decide.
//
// SchedulerCore queues jobs itself and hands the rest to its parts, one concept each:
//   SpecCheck       a spec from outside checked and its scene built, made a ValidatedJob (spec_check.h)
//   JobEvents       WatchJob subscriptions, events published in the store's order (job_events.h)
//   RunningJobs     each running job parsed once, and its measured tile cost (running_jobs.h)
//   WorkerRegistry  the workers, up or down or quarantined, probes and heartbeats (worker_registry.h)
//   Dispatcher      slots, claiming and sizing batches, calls in flight, results checked,
//                   quarantines (dispatcher.h); its spot checks' rounds are SpotCheckRounds'
//   Finisher        merging, writing and checking a finished job's frame (finisher.h)
//   DiskFullPause   dispatch paused while the disk refuses writes, resumed when it has room
//                   (disk_full_pause.h)
//   StoreOutage     the store's server away: nothing claimed or failed, results kept until it
//                   answers, interrupted merges looked at again then (store_outage.h)
//   SchedulerLease  on a store several schedulers share: this one's lease, the dead ones' units
//                   queued again (scheduler_lease.h)
//   EventRelay      likewise: the jobs' events to and from the other schedulers (event_relay.h)
//   RetentionSweeper  final jobs deleted with their files once older than --keep-finished
//                   (retention.h)
//   DependencyRelease  waiting jobs queued, or failed, as the jobs they wait for end
//                   (dependency_release.h)
//
// Locks: each part has its own mutex, and its header says what it guards. A part holds its lock
// while it calls another only along these arrows (A -> B: B is taken while A is held):
//   Dispatcher -> JobStore -> {WorkerRegistry, RunningJobs}   claiming a batch (batch sizing)
//   Dispatcher -> {WorkerRegistry, TileCancel}                claiming, cancelling calls in flight
//   JobEvents -> {JobStore, JobEventQueue, EventRelay,        publishing an event in store order
//                 its listeners (WebhookNotifier)}            (and logging it in the store)
//   Dispatcher -> DiskFullPause                               claiming (is dispatch paused?)
//   Dispatcher -> SpotCheckRounds -> WorkerRegistry          claiming or dropping a spot check
// The others (Finisher, RunningJobs, WorkerRegistry, JobStore, DiskFullPause, StoreOutage, the queues) are
// leaves: nothing is taken under them (StoreOutage's on_back runs with no lock held). The arrows make no cycle, so no two threads can deadlock on them.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <spdlog/logger.h>

#include "proto/farm.pb.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "server/common/asset_store.h"
#include "server/scheduler/assets/asset_grants.h"
#include "server/scheduler/assets/asset_quota.h"
#include "server/scheduler/dispatch/dispatcher.h"
#include "server/scheduler/events/event_relay.h"
#include "server/scheduler/events/job_events.h"
#include "server/scheduler/jobs/dependency_release.h"
#include "server/scheduler/jobs/disk_full_pause.h"
#include "server/scheduler/jobs/finisher.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/retention.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/jobs/spec_check.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/scheduler_lease.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/store_outage.h"
#include "server/scheduler/workers/tile_worker.h"
#include "server/scheduler/workers/worker_infos.h"
#include "server/scheduler/workers/worker_registry.h"

namespace farm {

// A new scheduler id, "HOST:PID:RANDOM": unique among the schedulers of one store, and says which
// machine and process in the store and the logs.
std::string make_scheduler_id();

// How a submitted job takes its place in the queue besides its priority (SubmitJobRequest): the
// jobs it waits for, caps over the job file's, and its owner's fair-share weight.
struct QueueTerms {
  std::vector<std::string> after = {};
  std::vector<std::string> after_any = {};
  std::string after_frames = {};
  JobCaps caps = {};  // each nonzero one replaces the job file's
  std::optional<std::int64_t> owner_weight_milli = {};  // the tokens file's weight; none: as it was
};

class SchedulerCore {
 public:
  // Opens (or creates) the data dir and resumes its jobs: tiles that were running are queued
  // again, done tiles stay done, jobs whose tiles are all done are merged.
  explicit SchedulerCore(SchedulerOptions options);
  ~SchedulerCore();  // stop()
  SchedulerCore(const SchedulerCore&) = delete;
  SchedulerCore& operator=(const SchedulerCore&) = delete;

  // Stops dispatching: calls in flight are cancelled and their tiles queued again (no attempt
  // counted), threads joined. Idempotent.
  void stop();

  const AssetStore& assets() const { return assets_; }
  // Uploads reserve their size here before they are written (--max-asset-store-bytes).
  AssetQuota& asset_quota() { return asset_quota_; }
  // The assets workers may fetch now (given to RemoteTileWorkers this core renders on).
  AssetGrants& grants() { return grants_; }
  const JobStore& store() const { return store_; }
  const std::string& scheduler_id() const { return scheduler_id_; }
  spdlog::logger& log() const { return *log_; }
  const SchedulerOptions& options() const { return options_; }

  // A spec from outside checked as `farm render` checks a job, and made ready to queue
  // (SpecCheck::check: the limits, the assets, the job parsed, its scene built). Throws as it says.
  ValidatedJob check(const v1::JobSpec& spec) const { return specs_.check(spec); }
  // Queues a job: the only way in, whoever checked it. DiskFull when the store has no room for it
  // (nothing of it is kept). A `watcher` is subscribed to the job before it is queued, so it sees
  // every event of the job (pass it to unwatch() when done). `owner` is recorded with the job:
  // the name of the caller's token.
  // `terms`: its dependencies (ServiceError INVALID_ARGUMENT for one that names no job), caps
  // and owner's weight.
  v1::Job submit(ValidatedJob job, int priority = 0, const std::shared_ptr<JobEventQueue>& watcher = nullptr,
                 const std::string& owner = {}, const QueueTerms& terms = {});
  // The job with its dependencies and dependents (Job.after, ..., dependents).
  std::optional<v1::Job> get_job(const std::string& job_id) const;
  // Each active job with requirements no worker meets gets `unplaceable` set, saying why (the
  // workers read once for all of them).
  void explain_placement(std::span<v1::Job> jobs) const;
  // Drops the job's queued tiles and cancels its calls in flight. ServiceError NOT_FOUND.
  // `by`: who asked (the caller's token name), said in the job's log and its watchers' events.
  v1::Job cancel(const std::string& job_id, const std::string& by = {});
  // Operator actions, each announced to the job's watchers and its log as a JobUpdated naming
  // `by` (the caller's token name). ServiceError NOT_FOUND for an unknown job, FAILED_PRECONDITION
  // for one whose state the action does not apply to (proto/farm.proto says which).
  v1::Job pause(const std::string& job_id, bool paused, const std::string& by = {});
  v1::Job set_priority(const std::string& job_id, int priority, const std::string& by = {});
  v1::Job set_caps(const std::string& job_id, std::optional<int> max_workers, std::optional<int> max_units_in_flight,
                   const std::string& by = {});
  // More jobs for a job that has not started to wait for (JobDependencies::add): INVALID_ARGUMENT
  // for an unknown id or a cycle, FAILED_PRECONDITION for a job that has started.
  v1::Job add_dependencies(const std::string& job_id, const std::vector<std::string>& after,
                           const std::vector<std::string>& after_any, const std::string& by = {});
  // A FAILED or CANCELLED job's units that are not done rendered again (JobRecords::retry_job).
  RetriedJob retry(const std::string& job_id, const std::string& by = {});
  // A final job gone from the store with its files; returns the bytes freed.
  std::uintmax_t remove(const std::string& job_id);
  // Every final job that finished before `before_ms` (Unix ms) removed; returns how many (the
  // scheduler's --keep-finished).
  std::size_t remove_finished_before(std::int64_t before_ms);
  // The merged EXR or PNG of a frame once it is merged (no frame: the first, of a SUCCEEDED
  // job); nullopt otherwise.
  std::optional<std::filesystem::path> result_file(const std::string& job_id, bool preview,
                                                   std::optional<int> frame = std::nullopt) const;
  // The newest progressive preview of a frame of sample passes (ResultFiles::progressive_result).
  std::optional<std::filesystem::path> progressive_result(const std::string& job_id, int frame) const;
  // The video of a SUCCEEDED job that asked for one (output.video), kept under results/; nullopt
  // otherwise.
  std::optional<std::filesystem::path> video_file(const std::string& job_id) const;

  // Events of `job_id` (JobEvents::kEveryJob: of every job) from now on, kept in a queue of
  // `capacity`; pass the queue to unwatch() when done.
  std::shared_ptr<JobEventQueue> watch(const std::string& job_id, std::size_t capacity = SIZE_MAX);
  // A watch of one job begun with the job as it was then (JobEvents::subscribe_and_read): no event
  // in the queue shows the job older than `job`, and none after it is missed. `job` empty: no such
  // job (pass the queue to unwatch() all the same).
  struct WatchStart {
    std::shared_ptr<JobEventQueue> queue;
    std::optional<v1::Job> job;
  };
  WatchStart watch_from_now(const std::string& job_id, std::size_t capacity = SIZE_MAX);
  // Every event this scheduler publishes from now on, in order (JobEvents::listen: must not block).
  void listen(std::function<void(const v1::JobEvent&)> listener) { events_.listen(std::move(listener)); }
  // The dashboard's live image of a frame (ResultFiles::live_preview).
  std::optional<std::filesystem::path> live_preview(const std::string& job_id, int frame);
  // Units kept and failed, their rate and latency (the dashboard's /metrics).
  UnitMetrics::Snapshot unit_metrics() const { return dispatcher_.metrics().snapshot(); }
  void unwatch(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue);

  // Workers. A static worker is never dropped, only probed while down; a registered one is
  // dropped when it misses heartbeats, and its tiles are queued again.
  std::string add_worker(std::shared_ptr<TileWorker> worker, bool registered = false, WorkerFacts facts = {});
  void remove_worker(const std::string& worker_id, const std::string& reason);
  bool heartbeat(const std::string& worker_id);  // false: unknown worker (register again)
  std::size_t worker_count() const;
  // Every worker now: up or down, and quarantined with the reason.
  std::vector<WorkerStatus> workers() const;
  // The same with what each renders now, as ListWorkers answers (farm workers).
  std::vector<v1::WorkerInfo> worker_infos() const;

  // Jobs whose state is kept in memory now (RunningJobs): none once every job is final.
  std::size_t jobs_in_memory() const { return jobs_.count(); }

 private:
  // Merges the complete frames of every active job and ends those with all merged: the ones a
  // stop (at start) or an outage of the store (when it answers again) interrupted.
  void finish_active_jobs();
  // An operator's action on the job logged and announced to its watchers (JobUpdated).
  void announce(const std::string& job_id, const std::string& change, const std::string& by);
  // Jobs the release settled: announced, and a failed one's units in flight stopped.
  void settled(const std::vector<ReleasedJob>& jobs);

  // Declared in the order they are built: each part is given the ones above it.
  SchedulerOptions options_;
  AssetStore assets_;
  AssetQuota asset_quota_;
  AssetGrants grants_;
  JobStore store_;
  std::shared_ptr<spdlog::logger> log_;
  std::unique_ptr<FrameAssembly> assembly_;
  SpecCheck specs_;
  RunningJobs jobs_;
  JobEvents events_;
  DiskFullPause pause_;
  StoreOutage outage_;
  ResultFiles results_;
  Finisher finisher_;
  WorkerRegistry workers_;
  Dispatcher dispatcher_;
  // This process among the schedulers of one store: host, process id and a random part.
  std::string scheduler_id_ = make_scheduler_id();
  std::unique_ptr<SchedulerLease> lease_;  // on a shared store (PostgreSQL) only
  std::unique_ptr<EventRelay> relay_;      // likewise: WatchJob's events to and from the others
  std::unique_ptr<RetentionSweeper> retention_;  // with options_.keep_finished
  std::unique_ptr<DependencyRelease> release_;
};

}  // namespace farm
