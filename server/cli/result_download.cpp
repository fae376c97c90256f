#include "server/cli/result_download.h"

#include <fmt/format.h>

#include <algorithm>

#include "renderer/util/input_error.h"
#include "server/cli/job_display.h"

namespace farm {

void download_results(SchedulerClient& client, const std::string& job_id, const ResultPath& where,
                      bool want_preview, std::optional<int> frame) {
  const auto fetch = [&](v1::ResultKind kind) {
    const std::filesystem::path file =
        client.fetch(job_id, kind, [&](const std::string& name) { return where(kind, name, frame.value_or(0)); }, frame);
    fmt::print("wrote {}\n", file.string());
  };
  fetch(v1::RESULT_KIND_EXR);
  if (!want_preview) return;
  try {
    fetch(v1::RESULT_KIND_PREVIEW);
  } catch (const InputError&) {
    // The job asked for no preview.
  }
}

namespace {

// The job's video, once it has SUCCEEDED, as `video` asks.
void download_video(SchedulerClient& client, const v1::Job& job, const ResultPath& where, VideoDownload video) {
  if (video == VideoDownload::none || job.state() != v1::JOB_STATE_SUCCEEDED) return;
  try {
    const std::filesystem::path file = client.fetch(
        job.job_id(), v1::RESULT_KIND_VIDEO, [&](const std::string& name) { return where(v1::RESULT_KIND_VIDEO, name, 0); });
    fmt::print("wrote {}\n", file.string());
  } catch (const InputError&) {
    if (video == VideoDownload::required) throw;
    // The job asked for no video.
  }
}

}  // namespace

int download_job_results(SchedulerClient& client, const v1::Job& job, const ResultPath& where, bool want_preview,
                         VideoDownload video) {
  const std::string& id = job.job_id();
  if (frames_of(job).empty()) {
    if (job.state() != v1::JOB_STATE_SUCCEEDED) {
      throw InputError(fmt::format("job {} is {}: nothing to fetch yet{}", id, to_string(job.state()),
                                   job.failure_reason().empty() ? "" : " (" + job.failure_reason() + ")"));
    }
    download_results(client, id, where, want_preview);
    return 1;
  }
  // A job with frames: every frame merged so far, while the job renders the rest.
  int fetched = 0, waiting = 0;
  for (std::int64_t f = job.frame_first(); f <= job.frame_last(); f += std::max(1, job.frame_step())) {
    try {
      download_results(client, id, where, want_preview, static_cast<int>(f));
      ++fetched;
    } catch (const InputError&) {
      if (job.state() == v1::JOB_STATE_SUCCEEDED) throw;  // every frame is there
      ++waiting;
    }
  }
  if (waiting > 0) {
    fmt::print("job {} is {}: {} of its {} frames fetched, {} not rendered yet{}\n", id, to_string(job.state()),
               fetched, job.frames_total(), waiting,
               job.failure_reason().empty() ? "" : " (" + job.failure_reason() + ")");
  }
  if (fetched == 0) throw InputError(fmt::format("job {} is {}: no frame to fetch yet", id, to_string(job.state())));
  download_video(client, job, where, video);
  return fetched;
}

}  // namespace farm
