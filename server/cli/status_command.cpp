#include "server/cli/status_command.h"

#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {
namespace {

// job_id empty: list every job.
int run_status(const JobOnScheduler& o) {
  SchedulerClient client(resolve_scheduler_connection(o.scheduler));
  if (!o.job_id.empty()) {
    print_job(client.get(o.job_id));
    return 0;
  }
  const std::vector<v1::Job> jobs = client.list();
  if (jobs.empty()) {
    fmt::print("no jobs on {}\n", client.address());
    return 0;
  }
  fmt::print("{:<36} {:<20} {:<10} {:>13} {:<8} {:>11} {}\n", "ID", "NAME", "STATE", "PROGRESS", "ENGINE", "SIZE",
             "SUBMITTED");
  for (const v1::Job& job : jobs) {
    fmt::print("{:<36} {:<20} {:<10} {:>13} {:<8} {:>11} {}\n", job.job_id(), job.name().substr(0, 20),
               to_string(job.state()), progress_of(job), job.engine(), fmt::format("{}x{}", job.width(), job.height()),
               local_time(job.submitted_at()));
  }
  return 0;
}

}  // namespace

void add_status_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<JobOnScheduler>();
  CLI::App* status = app.add_subcommand("status", "List the scheduler's jobs, or show one");
  status->add_option("id", o->job_id, "Job id (default: list all jobs)");
  add_scheduler_connection_options(*status, o->scheduler);
  commands.add(status, [o] { return run_status(*o); });
}

}  // namespace farm
