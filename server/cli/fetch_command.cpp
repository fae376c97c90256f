#include "server/cli/fetch_command.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "renderer/scene/input_error.h"
#include "server/cli/job_display.h"
#include "server/cli/result_download.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {
namespace {

struct FetchOptions {
  JobOnScheduler target;
  std::filesystem::path output_dir = ".";
};

int run_fetch(const FetchOptions& o) {
  const std::string& job_id = o.target.job_id;
  SchedulerClient client(resolve_scheduler_connection(o.target.scheduler));
  const v1::Job job = client.get(job_id);
  const auto where = [&](v1::ResultKind kind, const std::string& name) {
    const std::string fallback = job.name() + (kind == v1::RESULT_KIND_EXR ? ".exr" : ".png");
    return o.output_dir / (name.empty() ? fallback : name);
  };
  if (frames_of(job).empty()) {
    if (job.state() != v1::JOB_STATE_SUCCEEDED) {
      throw InputError(fmt::format("job {} is {}: nothing to fetch yet{}", job_id, to_string(job.state()),
                                   job.failure_reason().empty() ? "" : " (" + job.failure_reason() + ")"));
    }
    download_results(client, job_id, where, true);
    return 0;
  }
  // A job with frames: every frame merged so far, while the job renders the rest.
  int fetched = 0, waiting = 0;
  for (std::int64_t f = job.frame_first(); f <= job.frame_last(); f += std::max(1, job.frame_step())) {
    try {
      download_results(client, job_id, where, true, static_cast<int>(f));
      ++fetched;
    } catch (const InputError& e) {
      if (job.state() == v1::JOB_STATE_SUCCEEDED) throw;  // every frame is there
      ++waiting;
    }
  }
  if (waiting > 0) {
    fmt::print("job {} is {}: {} of its {} frames fetched, {} not rendered yet{}\n", job_id, to_string(job.state()),
               fetched, job.frames_total(), waiting,
               job.failure_reason().empty() ? "" : " (" + job.failure_reason() + ")");
  }
  if (fetched == 0) throw InputError(fmt::format("job {} is {}: no frame to fetch yet", job_id, to_string(job.state())));
  return 0;
}

}  // namespace

void add_fetch_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<FetchOptions>();
  CLI::App* fetch = app.add_subcommand("fetch", "Download a job's EXR and preview (with frames: every frame merged so far)");
  add_job_on_scheduler_options(*fetch, o->target);
  fetch->add_option("-o,--output", o->output_dir, "Folder to write into")->capture_default_str();
  commands.add(fetch, [o] { return run_fetch(*o); });
}

}  // namespace farm
