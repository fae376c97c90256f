#include "server/scheduler/jobs/result_files.h"

#include <fmt/format.h>

#include <climits>

#include "renderer/image/preview.h"
#include "renderer/job/video_format.h"
#include "server/common/job_state.h"

namespace farm {

namespace fs = std::filesystem;

fs::path ResultFiles::progressive_file(const std::string& job_id, int frame) const {
  return dir(job_id) / "progress" / fmt::format("{}.png", frame);
}

MergedFiles ResultFiles::files_of(const std::string& job_id, const JobInfo& info, int frame) const {
  const bool framed = info.job->frames.has_value();
  const auto numbered = [&](const fs::path& pattern) {
    return framed && !pattern.empty() ? fs::path(frame_file_name(pattern.string(), frame)) : pattern;
  };
  if (!info.files.exr.empty()) return {numbered(info.files.exr), numbered(info.files.preview)};
  std::string stem = numbered(info.job->output_patterns.image.filename()).stem().string();
  if (stem.empty() || stem.starts_with(".")) stem = "image";
  const fs::path folder = dir(job_id) / std::to_string(frame);
  return {folder / (stem + ".exr"), folder / (stem + ".png")};
}

fs::path ResultFiles::video_path(const std::string& job_id, const JobInfo& info) const {
  if (!info.video.empty()) return info.video;
  // Kept as results/<job id>/<the video's file name>, beside the frames' folders.
  const fs::path& asked = info.job->output.video;
  std::string name = asked.filename().string();
  if (name.empty() || name.starts_with(".")) name = "video" + asked.extension().string();
  return dir(job_id) / name;
}

std::optional<fs::path> ResultFiles::result_file(const std::string& job_id, bool preview, std::optional<int> frame) const {
  const std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (!job) return std::nullopt;
  const int f = frame.value_or(job->frame_first());
  // Without a frame, the job's first once it succeeded; a frame named, as soon as it is merged.
  if (frame ? !store_.frames().is_frame_merged(job_id, f) : job->state() != v1::JOB_STATE_SUCCEEDED) return std::nullopt;
  const auto find_in = [&](const fs::path& dir) -> std::optional<fs::path> {
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (name.starts_with(".") || !e.is_regular_file(ec)) continue;
      if (e.path().extension() == (preview ? ".png" : ".exr")) return e.path();
    }
    return std::nullopt;
  };
  if (auto file = find_in(dir(job_id) / std::to_string(f))) return file;
  // A store from before frames kept a still's files in the job's folder itself.
  if (f == 0) return find_in(dir(job_id));
  return std::nullopt;
}

std::optional<fs::path> ResultFiles::progressive_result(const std::string& job_id, int frame) const {
  if (store_.frames().is_frame_merged(job_id, frame)) return result_file(job_id, true, frame);
  const fs::path file = progressive_file(job_id, frame);
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return std::nullopt;
  return file;
}

std::optional<fs::path> ResultFiles::video_file(const std::string& job_id) const {
  const std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (!job || job->state() != v1::JOB_STATE_SUCCEEDED) return std::nullopt;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir(job_id), ec)) {
    if (e.path().filename().string().starts_with(".") || !e.is_regular_file(ec)) continue;
    if (video_format_of(e.path())) return e.path();
  }
  return std::nullopt;
}

std::optional<fs::path> ResultFiles::live_preview(const std::string& job_id, int frame) {
  if (store_.frames().is_frame_merged(job_id, frame)) return result_file(job_id, true, frame);
  if (!assembly_.reads_parts_back()) return std::nullopt;
  // A job that has ended shows its merged frames only: nothing of it is kept in memory any more,
  // and a viewer must not bring it back.
  const std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (!job || is_final(job->state())) return std::nullopt;
  const std::shared_ptr<const JobInfo> info = jobs_.get(job_id);
  if (info->passes() > 1) return progressive_result(job_id, frame);
  const std::vector<FramePart> parts = store_.frames().frame_parts(job_id, frame, 1);
  if (parts.empty()) return std::nullopt;
  const fs::path file = dir(job_id) / "live" / fmt::format("{}.png", frame);
  std::lock_guard lock(live_mutex_);
  LivePreview& live = live_[{job_id, frame}];
  const auto now = std::chrono::steady_clock::now();
  std::error_code ec;
  // Made again only when more units are done, and not more often than kPartialEvery: however
  // many viewers ask, the merge reads each frame's parts a few times a second at most.
  if (live.parts != parts.size() && (now - live.made >= kPartialEvery || !fs::exists(file, ec))) {
    fs::create_directories(file.parent_path());
    write_preview(assembly_.assemble_partial(job_id, info->frame(frame), parts), file);
    live = {parts.size(), now};
  }
  return file;
}

void ResultFiles::forget_live(const std::string& job_id) {
  {
    std::lock_guard lock(live_mutex_);
    live_.erase(live_.lower_bound({job_id, INT_MIN}), live_.lower_bound({job_id + '\0', INT_MIN}));
  }
  std::error_code ignored;
  fs::remove_all(dir(job_id) / "live", ignored);
}

}  // namespace farm
