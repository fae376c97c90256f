#pragma once
// Downloading a finished job's EXR and preview (`farm fetch`, `farm submit --wait`).
#include <filesystem>
#include <functional>
#include <string>

#include "server/client/scheduler_client.h"

namespace farm {

// Where to write a result: given its kind, the name the scheduler suggests (may be empty) and its
// frame (a still's: 0).
using ResultPath = std::function<std::filesystem::path(v1::ResultKind, const std::string& name, int frame)>;

// Fetches the EXR and, when `want_preview`, the preview (none is fine: the job may not have
// one), printing "wrote PATH" for each.
// `frame`: that frame of a job with frames; none: the job's first.
void download_results(SchedulerClient& client, const std::string& job_id, const ResultPath& where,
                      bool want_preview, std::optional<int> frame = std::nullopt);

// Whether download_job_results fetches the job's video (once the job has SUCCEEDED): not at all,
// when the job has one (`farm fetch`, which has no job file to say), or always (an error if none).
enum class VideoDownload { none, if_any, required };

// Every result of `job` there is now: a still's once it succeeded (InputError before), each
// merged frame of a job with frames, those still rendering counted and said. Returns how many
// frames (a still: 1) were written; InputError when none could be. Then the video, as `video` says.
int download_job_results(SchedulerClient& client, const v1::Job& job, const ResultPath& where, bool want_preview,
                         VideoDownload video = VideoDownload::none);

}  // namespace farm
