#include "server/cli/fetch_command.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "renderer/util/input_error.h"
#include "server/cli/result_download.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"
#include "server/common/plain_file_name.h"

namespace farm {
namespace {

struct FetchOptions {
  JobOnScheduler target;
  std::filesystem::path output_dir = ".";
};

int run_fetch(const FetchOptions& o) {
  SchedulerClient client(resolve_scheduler_connection(o.target.scheduler));
  const v1::Job job = client.get(client.resolve_job_id(o.target.job_id));
  download_job_results(client, job,
                       [&](v1::ResultKind kind, const std::string& name, int) {
                         // Both names come from the scheduler: each is one plain file name in -o,
                         // whatever it says ("../../x" included).
                         const std::string fallback =
                             plain_file_name(job.name(), "job-" + job.job_id().substr(0, 12)) +
                             (kind == v1::RESULT_KIND_EXR     ? ".exr"
                              : kind == v1::RESULT_KIND_VIDEO ? ".mp4"
                                                              : ".png");
                         return o.output_dir / (name.empty() ? fallback : plain_file_name(name, fallback));
                       },
                       true, VideoDownload::if_any);
  return 0;
}

}  // namespace

void add_fetch_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<FetchOptions>();
  CLI::App* fetch = app.add_subcommand(
      "fetch",
      "Download a job's EXR and preview (with frames: every frame merged so far, and its video once it is done)");
  add_job_on_scheduler_options(*fetch, o->target);
  fetch->add_option("-o,--output", o->output_dir, "Folder to write into")->capture_default_str();
  commands.add(fetch, [o] { return run_fetch(*o); });
}

}  // namespace farm
