#pragma once
// The scheduler core and one in-process worker in one object, no sockets: what `farm render`
// runs, so that a local render and a farm render go through the same dispatch, tile and merge
// code. What a single process need not do, it skips: the job store lives in memory, tiles are
// pasted into the frame as rendered (no encoding, no files), the models load once.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "proto/farm.pb.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/scene_builder.h"
#include "server/client/job_submission.h"
#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

struct EmbeddedFarmOptions {
  // Assets and scenes of run()'s jobs (the job store and the tiles live in memory); empty: a
  // fresh folder under the temp dir, removed at the end.
  std::filesystem::path data_dir;
  int threads = 0;                 // the in-process worker's render threads; 0 = all cores
  ExrPixelType exr_type = ExrPixelType::Half;
  std::chrono::milliseconds batch_target = SchedulerOptions{}.batch_target;
  // Units of at least this many pixels a side (unit_grid.h): one process has no other worker to
  // balance against, and a raster frame of 300 units of 32 px spent more on their bookkeeping
  // than on its pixels. Its render threads still share a unit's job tiles (sub-tiles).
  int min_unit_edge = 256;
};

struct EmbeddedResult {
  v1::Job job;                     // SUCCEEDED, FAILED (failure_reason) or CANCELLED
  std::filesystem::path exr, preview;  // empty unless SUCCEEDED (and preview unless written)
  std::filesystem::path video;         // the job's output.video, once SUCCEEDED; empty: none
  // run_local with keep_frame: the merged frame, and the scene it was rendered from.
  std::optional<TileBuffer> frame;
  std::shared_ptr<const PreparedScene> scene;
};

// How run_local treats its job.
struct LocalRunOptions {
  bool write_preview = true;  // the job's output.preview, when it names one
  bool keep_frame = false;    // EmbeddedResult::frame and ::scene filled in
  std::optional<LoadedScene> loaded;  // the job's load_job_scene, done already; empty: run_local loads
};

class EmbeddedFarm {
 public:
  explicit EmbeddedFarm(EmbeddedFarmOptions options = {});
  ~EmbeddedFarm();
  EmbeddedFarm(const EmbeddedFarm&) = delete;
  EmbeddedFarm& operator=(const EmbeddedFarm&) = delete;

  // Puts an asset into the farm's store; returns its SHA-256.
  std::string add_asset(std::string_view bytes);
  std::string add_asset_file(const std::filesystem::path& file);

  using Progress = std::function<void(const v1::Job&)>;

  // What `farm render` runs: a job already parsed (`submission.job`, overrides applied) whose
  // models are loaded from where they lie, once: the scene built here is the one the worker
  // renders and the merge validates. Tiles stay in memory; the EXR and preview are written
  // once, to the job's output paths. Waits for a final state, calling `progress` with the job
  // after every event of it, the final state included. InputError for a model that fails to load.
  EmbeddedResult run_local(const JobSubmission& submission, const Progress& progress = {},
                           LocalRunOptions options = {});

  // A job as a client sends it (its files added with add_asset first), validated like
  // SchedulerCore::submit; its EXR and preview are written under the data dir.
  EmbeddedResult run(const v1::JobSpec& spec, const Progress& progress = {});

  SchedulerCore& core() { return *core_; }
  InProcessTileWorker& worker() { return *worker_; }

  // For a process about to end without destroying this farm (exit_abandoning_calls): removes its
  // scratch folder, when it made one, the one thing the kernel would not take back. Call it once
  // no job is running; the farm must not be used after it.
  void remove_scratch_folder();

 private:
  // Waits for the job submitted with `queue` as its watcher to end.
  v1::Job wait(const v1::Job& submitted, const std::shared_ptr<JobEventQueue>& queue,
               const Progress& progress);

  std::filesystem::path data_dir_;
  bool remove_data_dir_ = false;
  std::shared_ptr<InProcessTileWorker> worker_;
  std::unique_ptr<SchedulerCore> core_;
};

}  // namespace farm
