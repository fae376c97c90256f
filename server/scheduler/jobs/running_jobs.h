#pragma once
// What the scheduler keeps in memory of each job it runs, from its submission until it is final:
// the job parsed once (JobInfo) and what its tiles cost to render (the dispatcher sizes batches
// by it). After a restart, a job of an earlier process is read back from the store on first use.
//
// Lock: RunningJobs::mutex_ guards both maps and is a leaf (the store is read, and a job parsed,
// outside it). The dispatcher reads tile costs under its own lock and the job store's (batch
// sizing), never the other way round.
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/job.h"
#include "server/common/asset_store.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/job_merger.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

struct JobInfo {
  std::shared_ptr<const v1::JobSpec> spec;
  std::string scene_hash;
  std::shared_ptr<const Job> job;
  std::shared_ptr<const PreparedScene> scene;  // null: the merge builds one if it needs it
  // Empty: results/<job id>/<stem>.exr and .png. A job with frames holds patterns here (a '#'
  // run for the frame number, as the job's output).
  MergedFiles files;
  // The job's output.video: empty, results/<job id>/<its file name>; else where its submitter said.
  std::filesystem::path video;
  std::function<void(int frame, TileBuffer&&)> merged;

  // The frame `f` of the job's tiles: its image, AOVs and sample passes (the same for every frame).
  FrameLayout frame(int f) const;
  int passes() const { return pass_count(job->render); }
};

class RunningJobs {
 public:
  RunningJobs(const JobStore& store, const AssetStore& assets, std::filesystem::path data_dir)
      : store_(store), assets_(assets), data_dir_(std::move(data_dir)) {}

  // Keeps a job being queued; returns the one kept (an earlier one for the same id wins).
  std::shared_ptr<const JobInfo> add(const std::string& job_id, std::shared_ptr<const JobInfo> info);
  // The job's JobInfo; one an earlier process queued is read from the store, materialized and
  // parsed once (and kept only while the job is active: a late call about a final job must not
  // bring it back for good). std::runtime_error when the store does not have it.
  std::shared_ptr<const JobInfo> get(const std::string& job_id);

  // What one of the job's tiles took to render, as a batch measured it: the estimate follows the
  // recent batches (tiles differ across a frame).
  void add_unit_cost(const std::string& job_id, double ms);
  std::optional<double> unit_cost(const std::string& job_id) const;  // nullopt: none measured yet

  // The job is final: its memory goes. Returns how many jobs are still kept.
  std::size_t forget(const std::string& job_id);
  // Jobs kept in memory now (their JobInfo or their tile cost).
  std::size_t count() const;

 private:
  const JobStore& store_;
  const AssetStore& assets_;
  const std::filesystem::path data_dir_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const JobInfo>> jobs_;
  std::map<std::string, double> ms_per_tile_;
};

}  // namespace farm
