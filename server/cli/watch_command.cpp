#include "server/cli/watch_command.h"

#include <memory>
#include <string>

#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {

void add_watch_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<JobOnScheduler>();
  CLI::App* watch = app.add_subcommand("watch", "Follow a job with a progress bar until it ends");
  add_job_on_scheduler_options(*watch, *o);
  watch->footer("Exit codes: 0 the job succeeded, 1 it failed or was cancelled.");
  commands.add(watch, [o] {
    SchedulerClient client(resolve_scheduler_connection(o->scheduler));
    const v1::Job last = follow(client, o->job_id);
    print_job(last);
    return exit_code_of(last);
  });
}

}  // namespace farm
