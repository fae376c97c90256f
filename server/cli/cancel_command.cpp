#include "server/cli/cancel_command.h"

#include <fmt/format.h>

#include <memory>
#include <string>

#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {

void add_cancel_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<JobOnScheduler>();
  CLI::App* cancel = app.add_subcommand("cancel", "Cancel a job: its queued tiles are dropped, running ones stopped");
  add_job_on_scheduler_options(*cancel, *o);
  commands.add(cancel, [o] {
    SchedulerClient client(resolve_scheduler_connection(o->scheduler));
    const v1::Job job = client.cancel(client.resolve_job_id(o->job_id));
    fmt::print("job {}: {} ({})\n", job.job_id(), to_string(job.state()), progress_of(job));
    return 0;
  });
}

}  // namespace farm
