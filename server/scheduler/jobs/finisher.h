#pragma once
// The end of each frame and of a job: once a frame's tiles are all done, the frame is assembled
// (FrameAssembly), written (the EXR and the preview, job_merger.h), marked merged and announced
// (FrameFinished), while the job's other frames render on. Once every frame is merged, the job is
// checked against Embree when it asks for it, its video made when it asks for one, and marked
// SUCCEEDED (FAILED when any of that throws). A part whose kept data is damaged
// (DamagedParts: its file missing, truncated or failing its checksum) fails nothing: its tiles are
// queued again (UnitQueue::requeue_parts), the job stays running and is merged once they are done.
// A final job's memory and kept tiles then go (release()), whichever way it ended. A merge the disk
// refuses (DiskFull: the frame's files or the store's final mark) fails nothing either: the pause
// is told (disk_full_pause.h), the job stays running with its tiles done, and it is merged again
// when dispatch resumes (retry_refused()). A store whose server is away (StoreUnavailable) fails
// nothing either: the job stays as it is, and is looked at again when the store answers
// (store_outage.h). While the disk stays full, make_room() frees the tiles of
// the youngest job holding some, so that the farm's own tiles never hold the disk for good.
// A job whose end takes long (its Embree check, its video) ends on a thread of its own
// (job_endings.h), so that the slot that merged its last frame goes back to rendering. Several
// schedulers of one store may find a frame complete, or a job's frames all merged, at once: the
// one that claims it in the store (SchedulerLeases::claim_frame_merge, claim_job_end) merges or ends it.
//
// Lock: Finisher::mutex_ guards merging_ (a job being merged, and whether to look again) and
// refused_ only, and is a leaf: the merge itself runs
// without it.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <spdlog/logger.h>

#include "server/scheduler/events/job_events.h"
#include "server/scheduler/jobs/disk_full_pause.h"
#include "server/scheduler/jobs/frame_assembly.h"
#include "server/scheduler/jobs/job_endings.h"
#include "server/scheduler/jobs/progressive_previews.h"
#include "server/scheduler/jobs/result_files.h"
#include "server/scheduler/jobs/running_jobs.h"
#include "server/scheduler/jobs/setbacks.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/store_outage.h"

namespace farm {

class Finisher {
 public:
  Finisher(const SchedulerOptions& options, JobStore& store, FrameAssembly& assembly, RunningJobs& jobs,
           ResultFiles& results, JobEvents& events, DiskFullPause& pause, StoreOutage& outage, spdlog::logger& log)
      : options_(options), store_(store), assembly_(assembly), jobs_(jobs), results_(results), events_(events),
        setbacks_(pause, outage), log_(log), previews_(store, assembly, events) {}

  // Merges `frame` of the job if its tiles are all done (no frame: every complete frame), and ends
  // the job once all are merged. A frame of sample passes not yet complete gets its progressive
  // preview when a pass more is done (progressive_previews.h). One caller merges a job at a time; another calling meanwhile
  // returns at once, and the first looks again for complete frames before it returns.
  void finish_if_complete(const std::string& job_id, std::optional<int> frame = std::nullopt);
  // The job is final: what is kept of it in memory goes, and its units' results too unless
  // `keep_units` (a FAILED or CANCELLED job, which a retry finishes with the units it has: they go
  // with the job, remove_files()). The embedded farm keeps none: nothing of it outlives it.
  void release(const std::string& job_id, bool keep_units = false);
  // A deleted job's files: its kept units and everything under results/<job id>. Returns the
  // bytes freed.
  std::uintmax_t remove_files(const std::string& job_id);
  // Merges again the jobs whose merge the disk refused (called when dispatch resumes).
  void retry_refused();
  // The disk is full and stays full (called while dispatch is paused): the youngest running job
  // that holds done tiles (the last the queue reaches: lowest priority, then latest submission)
  // gives them back, their files removed and their tiles queued again (no attempt counted), so
  // that older jobs can finish and merge. False when fewer than two jobs hold done tiles.
  bool make_room();
  // Done parts of the job were taken back (the dispatcher quarantined their worker).
  void parts_taken_back(const std::string& job_id);
  // Ends the thread of the jobs' long ends: one ending now gives up (its video stops), and they
  // stay RUNNING with their frames merged, for the next scheduler to end. Idempotent.
  void stop() { endings_.stop(); }
  // Called (without locks) when a merge queued tiles again: the dispatcher's slots are woken.
  void on_requeued(std::function<void()> f) { on_requeued_ = std::move(f); }

 private:
  // The complete ones of `frames` (of every frame when `every_frame`) merged, then the job
  // finished if all are; the previews of those of `frames` that are not complete made.
  void merge_complete(const std::string& job_id, const std::set<int>& frames, bool every_frame);
  // The frame's progressive preview, if a pass more is done. Damaged parts are rendered again; a
  // full disk throws DiskFull; anything else is logged (a preview is no part of the result).
  void refine_preview(const std::string& job_id, int frame);
  // False when the job cannot go on to its next frame now: failed, or tiles to render again.
  bool merge_frame(const std::string& job_id, int frame);
  // Every frame is merged: the job ends here, or on the endings' thread when that takes long.
  void finish(const std::string& job_id);
  // The job's Embree check, video and final mark, then its release; DiskFull and VideoStopped
  // are thrown, every other problem fails the job.
  void end_job(const std::string& job_id);
  // end_job on the endings' thread: a full disk reported and the job merged again once there is
  // room, a stop leaves the job as it is.
  void end_in_background(const std::string& job_id);
  void fail(const std::string& job_id, const std::string& reason);
  // Queues the damaged parts' tiles again; false when the job had none done any more (final).
  bool render_again(const std::string& job_id, const DamagedParts& damaged);
  // Tells the job's watchers that `taken` was queued again for `reason` (no attempt counted).
  void publish_requeued(const std::string& job_id, const std::vector<UnitBatch>& taken, const std::string& reason);
  // The job's output.video, once every frame is merged (video_encoder.h): where its submitter
  // said, or results/<job id>/<its file name>. std::exception when ffmpeg cannot make it.
  void make_video(const std::string& job_id, const JobInfo& info) const;


  const SchedulerOptions& options_;
  JobStore& store_;
  FrameAssembly& assembly_;
  RunningJobs& jobs_;
  ResultFiles& results_;
  JobEvents& events_;
  Setbacks setbacks_;  // a full disk or the store away told from other failures
  spdlog::logger& log_;
  std::mutex mutex_;
  struct Merging {
    bool again = false;        // a batch was done meanwhile: look again
    std::set<int> frames;      // the frames of those batches: only they can have completed
    bool every_frame = false;  // a caller without a frame (a restart, a retry): look at all
  };
  std::map<std::string, Merging> merging_;  // jobs being merged
  std::set<std::string> refused_;  // merges the disk refused, tried again by retry_refused()
  std::function<void()> on_requeued_;  // set once, before any merge
  ProgressivePreviews previews_;
  static constexpr unsigned kTrimEvery = 16;
  std::atomic<unsigned> released_{0};  // jobs released, for trimming the heap now and then
  // Declared last: its thread calls into the fields above, and is joined before they go.
  JobEndings endings_{[this](const std::string& job_id) { end_in_background(job_id); }};
};

}  // namespace farm
