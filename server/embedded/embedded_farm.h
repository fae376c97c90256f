#pragma once
// The scheduler core and one in-process worker in one object, no sockets: what `farm render`
// runs, so that a local render and a farm render go through the same dispatch, tile and merge
// code.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "proto/farm.pb.h"
#include "server/embedded/in_process_tile_worker.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

struct EmbeddedFarmOptions {
  std::filesystem::path data_dir;  // empty: a fresh folder under the temp dir, removed at the end
  int threads = 0;                 // the in-process worker's render threads; 0 = all cores
  ExrPixelType exr_type = ExrPixelType::Half;
  std::chrono::milliseconds batch_target = SchedulerOptions{}.batch_target;
};

struct EmbeddedResult {
  v1::Job job;                     // SUCCEEDED, FAILED (failure_reason) or CANCELLED
  std::filesystem::path exr, preview;  // under the data dir; empty unless SUCCEEDED
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

  // Submits (InputError / ServiceError as SchedulerCore::submit) and waits for a final state,
  // calling `progress` with the job after every event of it, the final state included.
  EmbeddedResult run(const v1::JobSpec& spec,
                     const std::function<void(const v1::Job&)>& progress = {});

  SchedulerCore& core() { return *core_; }
  InProcessTileWorker& worker() { return *worker_; }

 private:
  std::filesystem::path data_dir_;
  bool remove_data_dir_ = false;
  std::shared_ptr<InProcessTileWorker> worker_;
  std::unique_ptr<SchedulerCore> core_;
};

}  // namespace farm
