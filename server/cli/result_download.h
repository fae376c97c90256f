#pragma once
// Downloading a finished job's EXR and preview (`farm fetch`, `farm submit --wait`).
#include <filesystem>
#include <functional>
#include <string>

#include "server/client/scheduler_client.h"

namespace farm {

// Where to write a result: given its kind and the name the scheduler suggests (may be empty).
using ResultPath = std::function<std::filesystem::path(v1::ResultKind, const std::string& name)>;

// Fetches the EXR and, when `want_preview`, the preview (none is fine: the job may not have
// one), printing "wrote PATH" for each.
// `frame`: that frame of a job with frames; none: the job's first.
void download_results(SchedulerClient& client, const std::string& job_id, const ResultPath& where,
                      bool want_preview, std::optional<int> frame = std::nullopt);

}  // namespace farm
