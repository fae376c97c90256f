#include "server/cli/submit_command.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "renderer/job/job.h"
#include "server/cli/job_display.h"
#include "server/cli/job_file_options.h"
#include "server/cli/render_override_options.h"
#include "server/cli/result_download.h"
#include "server/cli/scheduler_target.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/job_state.h"

namespace farm {
namespace {

struct SubmitOptions {
  SchedulerConnectionFlags scheduler;
  std::filesystem::path job_file;
  JobLoadOptions load;
  RenderOverrides overrides;
  bool wait = false;
  int priority = 0;
  std::vector<std::string> after, after_any;  // ids or unique starts of them
  std::string after_frames;
  std::uint32_t max_workers = 0, max_units_in_flight = 0;
};

int run_submit(const SubmitOptions& o) {
  const JobSubmission submission = make_job_submission(o.job_file, o.load, o.overrides);
  SchedulerClient client(resolve_scheduler_connection(o.scheduler));
  const std::size_t uploaded = client.upload_missing(submission);
  v1::SubmitJobRequest request;
  request.set_priority(o.priority);
  for (std::string& id : client.resolve_job_ids(o.after)) request.add_after(std::move(id));
  for (std::string& id : client.resolve_job_ids(o.after_any)) request.add_after_any(std::move(id));
  if (!o.after_frames.empty()) request.set_after_frames(client.resolve_job_id(o.after_frames));
  request.set_max_workers(o.max_workers);
  request.set_max_units_in_flight(o.max_units_in_flight);
  const v1::Job job = client.submit(submission, std::move(request));
  fmt::print("{}\n", job.job_id());
  fmt::print(stderr, "submitted '{}' to {}: {} units, {} of {} assets uploaded\n", job.name(), client.address(),
             job.tiles_total(), uploaded, submission.spec.assets_size());
  // It waits for a worker that does not exist yet: said now, not left to a silent --wait.
  if (!job.unplaceable().empty()) fmt::print(stderr, "waiting: {}\n", job.unplaceable());
  if (job.state() == v1::JOB_STATE_WAITING) fmt::print(stderr, "waiting: {}\n", describe_dependencies(job));
  if (!o.wait) return 0;
  const v1::Job last = follow(client, job.job_id());
  if (last.state() != v1::JOB_STATE_SUCCEEDED) return exit_code_of(last);
  // Like `farm render`: the results land where the job's output section says.
  download_job_results(client, last,
                       [&](v1::ResultKind kind, const std::string&, int frame) {
                         if (kind == v1::RESULT_KIND_VIDEO) return submission.job.output.video;
                         const JobOutput& out = job_at_frame(submission.job, submission.job.frames ? frame : 0).output;
                         return kind == v1::RESULT_KIND_EXR ? out.image : out.preview;
                       },
                       !submission.job.output.preview.empty(),
                       submission.job.output.video.empty() ? VideoDownload::none : VideoDownload::required);
  return 0;
}

}  // namespace

void add_submit_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<SubmitOptions>();
  CLI::App* submit = app.add_subcommand("submit", "Send a job and its assets to a scheduler; prints the job id");
  add_job_file_options(*submit, o->job_file, o->load);
  add_scheduler_connection_options(*submit, o->scheduler);
  submit->add_flag("--wait", o->wait,
                   "Follow the job to its end, then download the EXR and preview (and the video) to the "
                   "job's output paths (exit 1 if the job fails or is cancelled)");
  submit->add_option("--priority", o->priority, "Higher runs first; equal priorities in submission order")
      ->capture_default_str();
  submit->add_option("--after", o->after,
                     "Wait for these jobs (ids or unique starts, comma-separated) to succeed; fail, naming the "
                     "job, if one fails or is cancelled")
      ->delimiter(',');
  submit->add_option("--after-any", o->after_any, "Wait for these jobs to end, however they end, then run")
      ->delimiter(',');
  submit->add_option("--after-frames", o->after_frames,
                     "Follow this job of frames frame by frame: frame N starts once its frame N is merged");
  submit->add_option("--max-workers", o->max_workers,
                     "At most this many workers render the job at once (0: no cap; overrides the job file's "
                     "limits.max_workers)")
      ->check(CLI::Range(0, kMaxJobCap));
  submit->add_option("--max-units-in-flight", o->max_units_in_flight,
                     "At most this many of its units are out at once (0: no cap; overrides "
                     "limits.max_units_in_flight)")
      ->check(CLI::Range(0, kMaxJobCap));
  add_render_override_options(*submit, o->overrides);
  submit->footer("Assets are content-addressed (SHA-256): only those the scheduler lacks are uploaded.");
  commands.add(submit, [o] { return run_submit(*o); });
}

}  // namespace farm
