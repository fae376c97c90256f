#include "server/cli/result_download.h"

#include <fmt/format.h>

#include "renderer/scene/input_error.h"

namespace farm {

void download_results(SchedulerClient& client, const std::string& job_id, const ResultPath& where,
                      bool want_preview, std::optional<int> frame) {
  const auto fetch = [&](v1::ResultKind kind) {
    const std::filesystem::path file =
        client.fetch(job_id, kind, [&](const std::string& name) { return where(kind, name); }, frame);
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

}  // namespace farm
