#include "server/embedded/embedded_farm.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <optional>
#include <sstream>

#include "renderer/job/scene_builder.h"
#include "server/common/job_state.h"
#include "server/common/read_whole_file.h"
#include "server/common/scene_hash.h"

namespace farm {

namespace fs = std::filesystem;
using SteadyClock = std::chrono::steady_clock;

EmbeddedFarm::EmbeddedFarm(EmbeddedFarmOptions options) : data_dir_(options.data_dir) {
  if (data_dir_.empty()) {
    static std::atomic<int> counter{0};
    data_dir_ = fs::temp_directory_path() / fmt::format("farm-embedded-{}-{}", ::getpid(), counter++);
    remove_data_dir_ = true;
  }
  fs::create_directories(data_dir_);
  SchedulerOptions s;
  s.data_dir = data_dir_;
  s.exr_type = options.exr_type;
  s.merge_threads = options.threads;
  // `farm render` shows a progress bar and a summary: its log is for warnings and errors.
  s.log_level = LogLevel::warn;
  s.in_memory = true;
  // One worker in the same process: it cannot die on its own, so a generous deadline is only a
  // guard; two tiles in flight keep its threads busy between tiles.
  s.tiles_per_worker = 2;
  s.batch_target = options.batch_target;
  s.min_unit_edge = options.min_unit_edge;
  s.whole_row_batches = true;
  TileRendererOptions r;
  r.blobs_dir = data_dir_ / "assets";  // the scheduler's own store: nothing to fetch
  r.cache_dir = data_dir_;             // scenes/<hash>/ shared with the scheduler's validation
  r.threads = options.threads;
  r.log_level = s.log_level;
  worker_ = std::make_shared<InProcessTileWorker>(r);
  // The scene validation built is the one the worker renders: the models load once.
  s.validated_scene = [worker = worker_](const std::string& hash, const Job& job, Scene scene,
                                          std::shared_ptr<ModelLibrary> models) {
    worker->renderer().adopt(hash, job, std::move(scene), std::move(models));
  };
  core_ = std::make_unique<SchedulerCore>(s);
  core_->add_worker(worker_);
}

EmbeddedFarm::~EmbeddedFarm() {
  core_->stop();
  core_.reset();
  remove_scratch_folder();
}

void EmbeddedFarm::remove_scratch_folder() {
  if (!remove_data_dir_) return;
  std::error_code ignored;
  fs::remove_all(data_dir_, ignored);
  remove_data_dir_ = false;
}

std::string EmbeddedFarm::add_asset(std::string_view bytes) { return core_->assets().add(bytes); }

std::string EmbeddedFarm::add_asset_file(const fs::path& file) {
  return add_asset(read_whole_file(file, "asset"));
}

EmbeddedResult EmbeddedFarm::run_local(const JobSubmission& submission, const Progress& progress,
                                       LocalRunOptions options) {
  const Job& job = submission.job;
  const std::string hash = scene_hash(submission.spec);
  LoadedScene loaded = options.loaded ? std::move(*options.loaded) : load_job_scene(job);
  const std::shared_ptr<const CachedScene> cached =
      worker_->renderer().adopt(hash, job, std::move(loaded.scene), std::move(loaded.models));
  ValidatedJob v;
  v.spec = submission.spec;
  v.scene_hash = hash;
  v.job = std::shared_ptr<const Job>(cached, &cached->job);
  v.scene = std::shared_ptr<const PreparedScene>(cached, &cached->prepared);
  // A job with frames writes each where its patterns say.
  const JobOutput& output = job.frames ? job.output_patterns : job.output;
  v.exr = output.image;
  if (options.write_preview) v.preview = output.preview;
  v.video = job.output.video;
  EmbeddedResult result;
  if (options.keep_frame) {
    // The job's first frame, and its scene.
    v.merged = [&result, first = job.frame](int frame, TileBuffer&& film) {
      if (frame == first) result.frame = std::move(film);
    };
    result.scene = v.scene;
  }
  const auto queue = std::make_shared<JobEventQueue>();
  result.job = wait(core_->submit(std::move(v), 0, queue), queue, progress);
  if (result.job.state() == v1::JOB_STATE_SUCCEEDED) {
    result.exr = job.output.image;
    if (options.write_preview) result.preview = job.output.preview;
    result.video = job.output.video;
  }
  return result;
}

EmbeddedResult EmbeddedFarm::run(const v1::JobSpec& spec, const Progress& progress) {
  // Subscribed before the job is queued: every event reaches `progress`, the last one final.
  const auto queue = std::make_shared<JobEventQueue>();
  EmbeddedResult result;
  result.job = wait(core_->submit(core_->check(spec), 0, queue), queue, progress);
  if (result.job.state() == v1::JOB_STATE_SUCCEEDED) {
    result.exr = core_->result_file(result.job.job_id(), false).value_or(fs::path());
    result.preview = core_->result_file(result.job.job_id(), true).value_or(fs::path());
    result.video = core_->video_file(result.job.job_id()).value_or(fs::path());
  }
  return result;
}

v1::Job EmbeddedFarm::wait(const v1::Job& submitted, const std::shared_ptr<JobEventQueue>& queue,
                           const Progress& progress) {
  // The job's final event ends the wait. The store is polled too, as a guard: a final state
  // whose event never came (it always comes; this only keeps a bug from hanging `farm render`)
  // ends it after a grace second.
  std::optional<SteadyClock::time_point> final_in_store;
  while (true) {
    v1::JobEvent event;
    if (queue->pop(event, std::chrono::milliseconds(100))) {
      if (progress) progress(event.job());
      if (is_final(event.job().state())) break;
      continue;
    }
    if (!is_final(core_->get_job(submitted.job_id())->state())) continue;
    if (!final_in_store) final_in_store = SteadyClock::now();
    if (SteadyClock::now() - *final_in_store > std::chrono::seconds(1)) break;
  }
  core_->unwatch(submitted.job_id(), queue);
  return *core_->get_job(submitted.job_id());
}

}  // namespace farm
