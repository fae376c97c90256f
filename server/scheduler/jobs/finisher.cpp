#include "server/scheduler/jobs/finisher.h"

#include <fmt/format.h>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <memory>
#include <vector>

#include "renderer/accel/accel_validation.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/preview.h"
#include "renderer/job/frame_range.h"
#include "renderer/job/scene_builder.h"
#include "renderer/job/video_format.h"
#include "server/common/free_memory.h"
#include "server/common/job_state.h"
#include "server/scheduler/jobs/setbacks.h"
#include "server/common/remove_tree.h"
#include "server/common/video_encoder.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

// The job's `validate.embree_rays` check: our BVH's hits against Embree's, on the scene the job
// was rendered from when this process built it (else built here). Empty when the job asks none.
std::string check_against_embree(const JobInfo& info) {
  const Job& job = *info.job;
  if (job.embree_rays <= 0) return {};
  std::shared_ptr<const PreparedScene> scene = info.scene;
  if (!scene) scene = std::make_shared<const PreparedScene>(build_scene(job));
  const AccelKind accel = accel_to_validate(job.render.accel);
  const AccelValidation v =
      validate_against_embree(*scene, job.render, accel, static_cast<std::uint64_t>(job.embree_rays));
  return fmt::format("{} ({} vs embree{})", v.summary(), to_string(accel),
                     validation_passes(v) ? "" : "; more hit/miss disagreements than 0.001% of rays");
}

}  // namespace

void Finisher::finish_if_complete(const std::string& job_id, std::optional<int> frame) {
  {
    std::lock_guard lock(mutex_);
    const auto [it, added] = merging_.try_emplace(job_id);
    if (!added) {
      // Another thread merges the job's frames: it looks again once done, at this frame too.
      it->second.again = true;
      if (frame) {
        it->second.frames.insert(*frame);
      } else {
        it->second.every_frame = true;
      }
      return;
    }
  }
  // The frames to look at. Only those of the batches done can have completed: looking at every
  // frame after each merge read all of a long job's tiles again and again (an eighth of a
  // 48-frame turntable's time).
  std::set<int> frames;
  if (frame) frames.insert(*frame);
  bool every_frame = !frame;
  for (;;) {
    bool refused = false;
    try {
      merge_complete(job_id, frames, every_frame);
      setbacks_.store_answered();
    } catch (const std::exception& e) {
      // The store away: looked at again when it answers (StoreOutage::on_back). The disk full:
      // the job stays as it is, its units done, until there is room for its frame.
      const Setback setback = setbacks_.report_current();
      if (setback == Setback::disk_full) log_.debug("job {}: merge refused: {}", job_id, e.what());
      if (setback == Setback::none) log_.error("job {}: merging: {}", job_id, e.what());
      refused = setback == Setback::disk_full;
    }
    std::lock_guard lock(mutex_);
    const auto it = merging_.find(job_id);
    if (it->second.again && !refused) {
      frames = std::move(it->second.frames);
      every_frame = it->second.every_frame;
      it->second = {};
      continue;
    }
    merging_.erase(it);
    if (refused) refused_.insert(job_id);
    return;
  }
}

void Finisher::retry_refused() {
  std::set<std::string> jobs;
  {
    std::lock_guard lock(mutex_);
    jobs.swap(refused_);
  }
  for (const std::string& id : jobs) finish_if_complete(id);
}

void Finisher::release(const std::string& job_id, bool keep_units) {
  if (!keep_units || options_.in_memory) assembly_.remove_job(job_id);
  results_.forget_live(job_id);  // its merged frames show instead
  previews_.forget_job(job_id);
  const std::size_t still_running = jobs_.forget(job_id);
  // What the job's submission, tiles and merge freed is held by the allocator's arenas (the
  // scheduler grew from 28 to 760 MB over 50 tiny jobs, half of it free memory): it goes back when
  // the farm falls idle, and every kTrimEvery jobs during a long burst.
  if (still_running == 0 || ++released_ % kTrimEvery == 0) return_free_memory_to_system();
}

void Finisher::merge_complete(const std::string& job_id, const std::set<int>& frames, bool every_frame) {
  const std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (!job || is_final(job->state())) return;
  std::vector<int> complete;
  if (every_frame) {
    complete = store_.frames().complete_frames(job_id, std::nullopt);
  } else {
    for (int f : frames) {
      for (int c : store_.frames().complete_frames(job_id, f)) complete.push_back(c);
    }
  }
  if (job->passes() > 1) {
    for (int f : frames) {
      if (std::find(complete.begin(), complete.end(), f) == complete.end()) refine_preview(job_id, f);
    }
  }
  for (int f : complete) {
    // Another scheduler of the store may have found it complete too: one of them merges it.
    if (!store_.leases().claim_frame_merge(job_id, f)) continue;
    if (!merge_frame(job_id, f)) return;
  }
  const v1::Job now = *store_.jobs().get_job(job_id);
  if (is_final(now.state()) || now.frames_done() < now.frames_total() || now.tiles_done() < now.tiles_total()) return;
  if (!store_.leases().claim_job_end(job_id)) return;  // another scheduler ends it
  finish(job_id);
}

bool Finisher::merge_frame(const std::string& job_id, int frame) {
  try {
    const std::shared_ptr<const JobInfo> info = jobs_.get(job_id);
    const std::vector<FramePart> parts = store_.frames().frame_parts(job_id, frame, info->passes());
    TileBuffer film = assembly_.assemble(job_id, info->frame(frame), parts);
    write_merged(film, results_.files_of(job_id, *info, frame), options_.exr_type, options_.merge_threads);
    if (!store_.frames().frame_merged(job_id, frame)) {
      // A worker was quarantined while the frame was merged, and some of its tiles taken back:
      // they are being rendered again, and the frame is merged once they are done.
      log_.warn("job {}: merge of frame {} abandoned, some of its tiles are to be rendered again", job_id, frame);
      return false;
    }
    if (info->merged) info->merged(frame, std::move(film));
    assembly_.frame_merged(job_id, frame);
    previews_.frame_merged(job_id, *info, frame);
    std::error_code ignored;
    fs::remove(results_.progressive_file(job_id, frame), ignored);  // its preview is the merged one now
    events_.publish(job_id, [&](v1::JobEvent& event) { event.mutable_frame_finished()->set_frame(frame); });
    log_.debug("job {}: frame {} merged from {} calls", job_id, frame, parts.size());
    return true;
  } catch (const DamagedParts& e) {
    render_again(job_id, e);  // or the job is final meanwhile (cancelled): nothing to render again
    return false;
  } catch (const std::exception& e) {
    rethrow_if_setback();  // not the job's fault: done again once it clears (setbacks.h)
    fail(job_id, fmt::format("merging the tiles of frame {}: {}", frame, e.what()));
    return false;
  }
}

void Finisher::finish(const std::string& job_id) {
  std::shared_ptr<const JobInfo> info;
  try {
    info = jobs_.get(job_id);
  } catch (const std::exception& e) {
    rethrow_if_setback();  // not the job's fault: done again once it clears (setbacks.h)
    fail(job_id, fmt::format("finishing the job: {}", e.what()));
    return;
  }
  if (info->job->embree_rays > 0 || !info->job->output.video.empty()) {
    endings_.add(job_id);  // or it is queued already
    return;
  }
  end_job(job_id);
}

void Finisher::end_in_background(const std::string& job_id) {
  try {
    end_job(job_id);
  } catch (const VideoStopped&) {
    log_.info("job {}: its video is made by the next scheduler (this one is stopping)", job_id);
  } catch (const std::exception& e) {
    // The store away: ended when it answers again (StoreOutage::on_back). The disk full: as a
    // merge the disk refused, the job stays running, ended once there is room.
    const Setback setback = setbacks_.report_current();
    if (setback == Setback::none) log_.error("job {}: ending: {}", job_id, e.what());
    if (setback == Setback::disk_full) {
      log_.debug("job {}: end refused: {}", job_id, e.what());
      std::lock_guard lock(mutex_);
      refused_.insert(job_id);
    }
  }
}

void Finisher::end_job(const std::string& job_id) {
  const std::optional<v1::Job> before = store_.jobs().get_job(job_id);
  if (!before || is_final(before->state())) return;  // cancelled while it waited
  v1::Job after;
  std::shared_ptr<const JobInfo> info;
  std::string validation;
  try {
    info = jobs_.get(job_id);
    validation = check_against_embree(*info);
  } catch (const std::exception& e) {
    rethrow_if_setback();  // not the job's fault: done again once it clears (setbacks.h)
    fail(job_id, fmt::format("checking against Embree: {}", e.what()));
    return;
  }
  if (!info->job->output.video.empty()) {
    // A video that cannot be made fails the job, with ffmpeg's words; its frames stay fetchable.
    try {
      make_video(job_id, *info);
    } catch (const VideoStopped&) {
      throw;  // the job stays as it is: the next scheduler makes its video
    } catch (const std::exception& e) {
      fail(job_id, fmt::format("making the video (output.video {}): {}", info->job->output.video.string(), e.what()));
      return;
    }
  }
  try {
    after = store_.jobs().finish_job(job_id, v1::JOB_STATE_SUCCEEDED, "", validation, unix_ms_now());
  } catch (const std::exception& e) {
    rethrow_if_setback();  // not the job's fault: done again once it clears (setbacks.h)
    fail(job_id, fmt::format("finishing the job: {}", e.what()));
    return;
  }
  if (!is_final(after.state())) {
    log_.warn("job {}: not finished, {} of its {} tiles are to be rendered again", job_id,
              after.tiles_total() - after.tiles_done(), after.tiles_total());
    return;
  }
  log_.info("job {} done: {} units, {} frame{} merged", job_id, after.tiles_total(), after.frames_total(),
            after.frames_total() == 1 ? "" : "s");
  events_.publish_state(after, before->state());
  release(job_id);
}

void Finisher::fail(const std::string& job_id, const std::string& reason) {
  const v1::JobState before = store_.jobs().get_job(job_id)->state();
  const v1::Job after = store_.jobs().finish_job(job_id, v1::JOB_STATE_FAILED, reason, "", unix_ms_now());
  log_.error("job {} failed: {}", job_id, after.failure_reason());
  if (after.state() != before) events_.publish_state(after, before);
  release(job_id, true);
}

void Finisher::refine_preview(const std::string& job_id, int frame) {
  try {
    const std::shared_ptr<const JobInfo> info = jobs_.get(job_id);
    const fs::path file = results_.progressive_file(job_id, frame);
    fs::create_directories(file.parent_path());
    previews_.update(job_id, *info, frame, file);
  } catch (const DamagedParts& e) {
    render_again(job_id, e);
  } catch (const std::exception& e) {
    rethrow_if_setback();  // not the job's fault: done again once it clears (setbacks.h)
    // A preview is no part of the result: the job goes on, and the next pass tries again.
    log_.warn("job {}: progressive preview of frame {}: {}", job_id, frame, e.what());
  }
}

void Finisher::parts_taken_back(const std::string& job_id) { previews_.parts_taken_back(job_id); }

bool Finisher::make_room() {
  std::optional<v1::Job> youngest;
  int holding = 0;
  for (const std::string& id : store_.jobs().active_jobs()) {
    const std::optional<v1::Job> job = store_.jobs().get_job(id);
    if (!job || job->tiles_done() == 0) continue;
    ++holding;
    // active_jobs() is in submission order: a later job of the same priority is younger.
    if (!youngest || job->priority() <= youngest->priority()) youngest = job;
  }
  if (holding < 2) return false;
  const std::string& id = youngest->job_id();
  std::set<std::uint32_t> done;
  for (const UnitRecord& t : store_.units().tiles(id)) {
    if (t.state == TileState::Done) done.insert(t.part);
  }
  if (done.empty()) return false;
  const std::vector<std::uint32_t> parts(done.begin(), done.end());
  // The files first: the store itself may need their room to take the tiles back. Should it fail
  // still, the tiles stay done without their files, and the merge renders them again
  // (DamagedParts), as after a crash.
  assembly_.free_parts(id, parts);
  const std::vector<UnitBatch> taken = store_.units().requeue_parts(id, parts);
  previews_.parts_taken_back(id);
  std::uint32_t tiles = 0;
  for (const UnitBatch& b : taken) tiles += b.count;
  log_.warn("the disk is full: the {} done tiles of job {} (the youngest of {} running jobs holding tiles) are "
            "thrown away to make room for the older ones, and rendered again later",
            tiles, id, holding);
  publish_requeued(id, taken, "the scheduler's disk is full: thrown away to make room for older jobs, rendered again");
  return true;
}

bool Finisher::render_again(const std::string& job_id, const DamagedParts& damaged) {
  std::vector<std::uint32_t> parts;
  for (const DamagedParts::Part& p : damaged.parts()) parts.push_back(p.part);
  const std::vector<UnitBatch> taken = store_.units().requeue_parts(job_id, parts);
  if (taken.empty()) return false;
  previews_.parts_taken_back(job_id);
  for (const DamagedParts::Part& p : damaged.parts()) {
    log_.warn("job {}: {}; its tiles are rendered again, not merged", job_id, p.problem);
  }
  publish_requeued(job_id, taken, "the scheduler's copy of the result is damaged: rendered again");
  if (on_requeued_) on_requeued_();
  return true;
}

void Finisher::publish_requeued(const std::string& job_id, const std::vector<UnitBatch>& taken,
                                const std::string& reason) {
  for (const UnitBatch& b : taken) {
    events_.publish(job_id, [&](v1::JobEvent& event) {
      v1::TileFailed& f = *event.mutable_tile_failed();
      f.set_tile_index(b.first);
      f.set_tile_count(b.count);
      f.set_reason(reason);
      f.set_will_retry(true);
    });
  }
}

void Finisher::make_video(const std::string& job_id, const JobInfo& info) const {
  VideoRequest request;
  for (int f : job_frames(*info.job)) request.frames.push_back(results_.files_of(job_id, info, f).preview);
  request.fps = info.job->frames ? info.job->frames->fps : 24.0;
  request.output = results_.video_path(job_id, info);
  request.stop_requested = [this] { return endings_.stop_requested(); };
  encode_video(request);
  log_.info("job {}: video of {} frames written to {}", job_id, request.frames.size(), request.output.string());
}

std::uintmax_t Finisher::remove_files(const std::string& job_id) {
  previews_.forget_job(job_id);
  return assembly_.remove_job(job_id) + remove_tree(results_.dir(job_id));
}

}  // namespace farm
