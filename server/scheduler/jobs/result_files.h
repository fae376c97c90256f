#pragma once
// Where a job's results lie under the data dir (docs/architecture.md, "The data dir"), and which of
// them a client may fetch now: results/<job id>/<frame>/ holds a merged frame's EXR and PNG (unless
// its submitter named the files), progress/<frame>.png a frame's newest progressive preview,
// live/<frame>.png the dashboard's image of a frame still rendering, and the job's video sits
// beside the frames' folders. Taken out of the Finisher, which writes them.
//
// Lock: live_mutex_ is a leaf, held while a live preview is made so that two viewers make it once.
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/job_merger.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

class ResultFiles {
 public:
  // Each part outlives this.
  ResultFiles(std::filesystem::path data_dir, JobStore& store, FrameAssembly& assembly, RunningJobs& jobs)
      : data_dir_(std::move(data_dir)), store_(store), assembly_(assembly), jobs_(jobs) {}

  // results/<job id>
  std::filesystem::path dir(const std::string& job_id) const { return data_dir_ / "results" / job_id; }
  // results/<job id>/progress/<frame>.png
  std::filesystem::path progressive_file(const std::string& job_id, int frame) const;
  // Where the job's frame goes: where its submitter said (the frame's number in its '#' run), or
  // results/<job id>/<frame>/<stem>.exr and .png.
  MergedFiles files_of(const std::string& job_id, const JobInfo& info, int frame) const;
  // Where the job's output.video goes: where its submitter said, or results/<job id>/<its name>.
  std::filesystem::path video_path(const std::string& job_id, const JobInfo& info) const;

  // The merged EXR or PNG of the job's `frame` once it is merged; without a frame, the first
  // frame of a SUCCEEDED job. nullopt otherwise.
  std::optional<std::filesystem::path> result_file(const std::string& job_id, bool preview,
                                                   std::optional<int> frame = std::nullopt) const;
  // The newest progressive preview (PNG) of the job's frame of sample passes, until it is merged;
  // then its preview. nullopt before its first pass is done.
  std::optional<std::filesystem::path> progressive_result(const std::string& job_id, int frame) const;
  // The video of a SUCCEEDED job that asked for one; nullopt otherwise.
  std::optional<std::filesystem::path> video_file(const std::string& job_id) const;
  // The dashboard's live image of a frame being rendered: its merged preview once merged, its
  // progressive preview for a frame of sample passes, else a PNG of the units done so far (made
  // again when more are done, at most every kPartialEvery). nullopt when there is none yet, or for
  // the embedded farm.
  std::optional<std::filesystem::path> live_preview(const std::string& job_id, int frame);
  // The job is final: its live previews go (its merged frames show instead).
  void forget_live(const std::string& job_id);

 private:
  // The units of a frame each live preview shows, and when it was made.
  struct LivePreview {
    std::size_t parts = 0;
    std::chrono::steady_clock::time_point made;
  };
  static constexpr auto kPartialEvery = std::chrono::milliseconds(250);

  std::filesystem::path data_dir_;
  JobStore& store_;
  FrameAssembly& assembly_;
  RunningJobs& jobs_;
  std::mutex live_mutex_;
  std::map<std::pair<std::string, int>, LivePreview> live_;  // by job and frame
};

}  // namespace farm
