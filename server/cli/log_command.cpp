#include "server/cli/log_command.h"

#include <fmt/format.h>

#include <memory>

#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {

namespace {

struct LogOptions {
  JobOnScheduler target;
  bool json = false;
};

}  // namespace

void add_log_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<LogOptions>();
  CLI::App* log = app.add_subcommand("log", "Show a job's event log: state changes, unit failures (worker and "
                                            "reason), retries, merged frames, operator actions");
  add_job_on_scheduler_options(*log, o->target);
  log->add_flag("--json", o->json, "One JSON object a line (farm.v1.JobLogEntry: number, at, event)");
  commands.add(log, [o] {
    SchedulerClient client(resolve_scheduler_connection(o->target.scheduler));
    for (const v1::JobLogEntry& e : client.log(client.resolve_job_id(o->target.job_id))) {
      if (o->json) {
        fmt::print("{}\n", json_of(e));
      } else {
        print_log_entry(e);
      }
    }
    return 0;
  });
}

}  // namespace farm
