#pragma once
// The scheduler without its gRPC plumbing: jobs in (validated), tiles out to workers, tiles back
// to disk, frames merged. `farm scheduler` serves it over gRPC (SchedulerService); `farm render`
// runs it in-process with one InProcessTileWorker (EmbeddedFarm). One pipeline, two front ends.
//
// Dispatch: every worker gets `tiles_per_worker` slots, each a thread that claims the next queued
// batch of tiles (JobStore::claim_next_batch: priority, then submission order, then tile index),
// renders it on its worker in one call with a deadline per tile, writes the result file, then
// marks the tiles done. A batch holds as many consecutive tiles of a grid row as make about
// `batch_target` of rendering by the job's measured tile costs (the worker threads' CPU time per
// tile, divided by the threads; one tile until a cost is known, and smaller batches toward the
// end of a job), so cheap tiles do not drown in per-call costs.
// A failed or late batch goes back to the queue with attempts + 1 and the reason (a tile that
// failed goes out alone from then on); at max_attempts the job fails with it. A worker that
// cannot be reached is marked down and probed every probe_interval before it gets tiles again.
// A job whose tiles are all done is merged into its EXR and preview.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/image/exr_io.h"
#include "renderer/prepared_scene.h"
#include "renderer/scene/job.h"
#include "renderer/scene/scene.h"
#include "server/common/asset_store.h"
#include "server/common/log.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/frame_assembly.h"
#include "server/scheduler/tile_worker.h"

namespace farm {

struct SchedulerOptions {
  std::filesystem::path data_dir;  // jobs.db, assets/, scenes/, tiles/, results/
  std::chrono::milliseconds tile_deadline = std::chrono::minutes(10);
  int max_attempts = 3;            // failed attempts of one tile before its job fails
  int tiles_per_worker = 2;        // calls in flight per worker, so it never idles between calls
  // Rendering time a call aims at; 0 sends one tile per call.
  std::chrono::milliseconds batch_target = std::chrono::milliseconds(200);
  std::chrono::milliseconds probe_interval = std::chrono::seconds(1);
  std::chrono::milliseconds heartbeat_interval = std::chrono::seconds(1);
  int missed_heartbeats = 3;       // a registered worker silent this many intervals is dropped
  ExrPixelType exr_type = ExrPixelType::Half;  // as `farm render` without --float
  // What the scheduler logs on stderr unless the operator chose (set_log_level): a server logs
  // info and up, the embedded farm of `farm render` only warnings and errors.
  LogLevel log_level = LogLevel::info;
  // The embedded farm of `farm render`: the job store lives in memory and finished tiles are
  // pasted into their frame as they arrive (InMemoryAssembly), so nothing outlives the process.
  // Off (the farm): jobs.db on disk, each batch a file before its tiles are marked done.
  bool in_memory = false;
  // Given each job's scene as submit() built it to validate the job: the embedded farm hands it
  // to its in-process worker, so that `farm render` loads the models once, not twice.
  std::function<void(const std::string& scene_hash, const Job& job, Scene scene)> validated_scene;
};

// A job submitted from this process, validated by its caller: parsed once, its scene built once
// (the embedded farm hands the same scene to its worker), its frame written where the caller
// says rather than under results/.
struct ValidatedJob {
  v1::JobSpec spec;                             // what the store records and workers are sent
  std::string scene_hash;                       // scene_hash(spec)
  std::shared_ptr<const Job> job;               // the spec's job, parsed
  std::shared_ptr<const PreparedScene> scene;   // reused by the merge's Embree check
  std::filesystem::path exr, preview;           // preview empty: none
  // Given the merged frame after its files are written (`farm render --show-bvh` draws on it).
  std::function<void(TileBuffer&&)> merged;
};

// A WatchJob subscription: events of one job, in order.
class JobEventQueue {
 public:
  // False when `timeout` passed with nothing to pop.
  bool pop(v1::JobEvent& event, std::chrono::milliseconds timeout);
  void push(const v1::JobEvent& event);

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<v1::JobEvent> events_;
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
  const JobStore& store() const { return store_; }
  const SchedulerOptions& options() const { return options_; }

  // Validates like `farm render` (asset refs, parse_job, loading the models) and queues the job.
  // ServiceError FAILED_PRECONDITION naming a missing asset; InputError for a bad job (the
  // message names the job file and the JSON path). A `watcher` is subscribed to the job before
  // it is queued, so it sees every event of the job (pass it to unwatch() when done).
  v1::Job submit(const v1::JobSpec& spec, int priority = 0,
                 const std::shared_ptr<JobEventQueue>& watcher = nullptr);
  // Queues a job its caller has validated (no asset check, no parse, no scene build here).
  v1::Job submit_validated(ValidatedJob job, int priority = 0,
                           const std::shared_ptr<JobEventQueue>& watcher = nullptr);
  std::optional<v1::Job> get_job(const std::string& job_id) const;
  // Drops the job's queued tiles and cancels its calls in flight. ServiceError NOT_FOUND.
  v1::Job cancel(const std::string& job_id);
  // The merged EXR or PNG of a SUCCEEDED job; nullopt otherwise.
  std::optional<std::filesystem::path> result_file(const std::string& job_id, bool preview) const;

  // Events of `job_id` from now on; pass the queue to unwatch() when done.
  std::shared_ptr<JobEventQueue> watch(const std::string& job_id);
  void unwatch(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue);

  // Workers. A static worker is never dropped, only probed while down; a registered one is
  // dropped when it misses heartbeats, and its tiles are queued again.
  std::string add_worker(std::shared_ptr<TileWorker> worker, bool registered = false);
  void remove_worker(const std::string& worker_id, const std::string& reason);
  bool heartbeat(const std::string& worker_id);  // false: unknown worker (register again)
  std::size_t worker_count() const;

 private:
  struct InFlight;
  struct WorkerEntry;
  struct JobInfo;  // what the core keeps of a job in memory while it runs

  void slot_loop(const std::shared_ptr<WorkerEntry>& w);
  // Adds a validated job to the store and the dispatch.
  v1::Job queue_job(int priority, const std::shared_ptr<JobEventQueue>& watcher,
                    std::shared_ptr<JobInfo> info);
  void handle_result(const std::shared_ptr<WorkerEntry>& w, const InFlight& call,
                     const grpc::Status& status, RenderedTiles& result);
  int batch_size_locked(const std::string& job_id, int queued_tiles) const;  // under mutex_
  void measured(const TileBatch& batch, const v1::TileStats& stats);  // a batch's cost per tile
  void finish_if_complete(const std::string& job_id);
  void merge(const std::string& job_id);
  void monitor_loop();
  // The job's JobInfo; after a restart built again from the store (materialized and parsed once).
  std::shared_ptr<const JobInfo> job_info(const std::string& job_id);
  void publish(const v1::JobEvent& event);
  // An event carrying the job as the store has it now, filled in by `fill`.
  void publish_with_job(const std::string& job_id, const std::function<void(v1::JobEvent&)>& fill);
  void publish_state(const v1::Job& job, v1::JobState from);
  void cleanup_job_files(const std::string& job_id);

  SchedulerOptions options_;
  AssetStore assets_;
  JobStore store_;
  std::shared_ptr<spdlog::logger> log_;
  std::unique_ptr<FrameAssembly> assembly_;

  mutable std::mutex mutex_;  // dispatcher state below
  std::condition_variable work_;
  bool stopping_ = false;
  std::uint64_t next_worker_ = 0;
  std::map<std::string, std::shared_ptr<WorkerEntry>> workers_;
  std::vector<std::thread> threads_;  // slots of every worker ever added, and the monitor
  std::set<std::shared_ptr<InFlight>> in_flight_;
  std::map<std::string, std::shared_ptr<const JobInfo>> jobs_;
  std::set<std::string> merging_;
  std::map<std::string, double> ms_per_tile_;  // per job: recent cost of a tile (measured())

  std::mutex watch_mutex_;
  std::multimap<std::string, std::shared_ptr<JobEventQueue>> watchers_;
};

}  // namespace farm
