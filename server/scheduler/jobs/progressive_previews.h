#pragma once
// A frame of sample passes refines as it renders: after each complete pass (every tile of passes
// 0 .. p done) the scheduler writes the frame's progressive preview, the sRGB PNG of the samples
// of those passes, and announces it (PassFinished). The fold of each frame in progress is kept,
// so a new pass costs one fold of its parts, not a fold of every pass again; a few frames' folds
// are kept at once (kKeptFrames, each 36 to 60 bytes a pixel), and a frame whose fold was let go
// folds its passes again from the files. Its preview is the same fold the merge makes, stopped
// early (PassAccumulator): what the viewer sees after the last pass is the merged frame.
//
// Calls for one job come one at a time (the finisher merges a job on one thread at a time); calls
// for different jobs may run at once. Lock: mutex_ guards the maps only and is a leaf; folds and
// writes run without it.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "renderer/image/pass_merge.h"
#include "server/scheduler/events/job_events.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

class ProgressivePreviews {
 public:
  static constexpr std::size_t kKeptFrames = 4;

  ProgressivePreviews(JobStore& store, FrameAssembly& assembly, JobEvents& events)
      : store_(store), assembly_(assembly), events_(events) {}

  // After a batch of `frame` was done: if more of its passes are complete than its newest preview
  // shows, and the frame is not complete (its merge makes the last preview), folds the new passes,
  // writes `file` (atomically) and publishes PassFinished. Nothing for a job of one pass, or an
  // assembly that cannot read parts back (the embedded farm's). Throws what the fold or the write
  // throws (DamagedParts, DiskFull): the preview is then made again after the next batch.
  void update(const std::string& job_id, const JobInfo& info, int frame, const std::filesystem::path& file);
  // The frame is merged: its last pass is announced now (just before its FrameFinished) unless it
  // already was, and its fold goes.
  void frame_merged(const std::string& job_id, const JobInfo& info, int frame);
  // Parts of the job were taken back (quarantine, damage, room on a full disk): its folds may
  // hold pixels no longer done, and go; later previews fold again from the files.
  void parts_taken_back(const std::string& job_id);
  // The job is final: everything of it goes.
  void forget_job(const std::string& job_id);

 private:
  using Key = std::pair<std::string, int>;  // job, frame
  struct Fold {
    PassAccumulator pixels;
    int passes = 0;  // folded: 0 .. passes - 1
    // The job's taken_back_ count when the fold was begun: parts taken back while it was out of
    // the cache (a quarantine runs on another thread) may be in it, and then it is not kept.
    std::uint64_t taken_back = 0;
  };
  // The frame's fold, taken out of the cache (the caller puts it back); a fresh one if none.
  std::unique_ptr<Fold> take(const Key& key);
  void put_back(const Key& key, std::unique_ptr<Fold> fold);
  void publish(const std::string& job_id, int frame, int pass, int passes);

  JobStore& store_;
  FrameAssembly& assembly_;
  JobEvents& events_;
  std::mutex mutex_;
  std::list<std::pair<Key, std::unique_ptr<Fold>>> folds_;  // most recently used first
  std::map<Key, int> announced_;  // the newest pass announced of each frame in progress
  std::map<std::string, std::uint64_t> taken_back_;  // parts_taken_back calls, by job
};

}  // namespace farm
