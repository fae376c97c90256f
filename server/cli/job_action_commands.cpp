#include "server/cli/job_action_commands.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <functional>
#include <optional>
#include <vector>
#include <memory>
#include <string>

#include "renderer/job/worker_requirements.h"
#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"
#include "server/common/disk_full.h"

namespace farm {

namespace {

struct PriorityOptions {
  JobOnScheduler target;
  int priority = 0;
};

struct LimitsOptions {
  JobOnScheduler target;
  std::optional<std::uint32_t> max_workers, max_units_in_flight;
};

struct DependOptions {
  JobOnScheduler target;
  std::vector<std::string> after, after_any;
};

// "max 1 worker, max 8 units in flight", or "no caps".
std::string caps_of(const v1::Job& job) {
  std::vector<std::string> caps;
  if (job.max_workers() > 0) caps.push_back(fmt::format("max {} worker{}", job.max_workers(), job.max_workers() == 1 ? "" : "s"));
  if (job.max_units_in_flight() > 0) caps.push_back(fmt::format("max {} units in flight", job.max_units_in_flight()));
  return caps.empty() ? "no caps" : fmt::format("{}", fmt::join(caps, ", "));
}

void print_state(const v1::Job& job, const std::string& what) {
  fmt::print("job {}: {}{} ({}, priority {})\n", job.job_id(), what.empty() ? "" : what + ", ", state_label(job),
             progress_of(job), job.priority());
}

// A command `name` on one job: `act` is given the client and the job's whole id.
void add_action(CLI::App& app, CommandTable& commands, const std::string& name, const std::string& help,
                const std::function<void(SchedulerClient&, const std::string&)>& act) {
  auto o = std::make_shared<JobOnScheduler>();
  CLI::App* command = app.add_subcommand(name, help);
  add_job_on_scheduler_options(*command, *o);
  commands.add(command, [o, act] {
    SchedulerClient client(resolve_scheduler_connection(o->scheduler));
    act(client, client.resolve_job_id(o->job_id));
    return 0;
  });
}

}  // namespace

void add_job_action_commands(CLI::App& app, CommandTable& commands) {
  add_action(app, commands, "cancel", "Cancel a job: its queued units are dropped, running ones stopped (farm retry renders them later)",
             [](SchedulerClient& client, const std::string& id) { print_state(client.cancel(id), ""); });
  add_action(app, commands, "pause",
             "Pause a queued or running job: none of its units is handed out until `farm resume`; units in "
             "flight finish",
             [](SchedulerClient& client, const std::string& id) { print_state(client.pause(id, true), ""); });
  add_action(app, commands, "resume", "Resume a paused job",
             [](SchedulerClient& client, const std::string& id) { print_state(client.pause(id, false), ""); });
  add_action(app, commands, "retry",
             "Render a failed or cancelled job's units that are not done (failed, queued or stopped), with "
             "their attempts counted from zero; done units and merged frames are kept",
             [](SchedulerClient& client, const std::string& id) {
               const v1::RetryJobResponse r = client.retry(id);
               print_state(r.job(), fmt::format("{} unit{} queued again", r.units_queued(), r.units_queued() == 1 ? "" : "s"));
             });
  add_action(app, commands, "delete",
             "Delete a finished, failed or cancelled job from the scheduler: its record, event log, kept "
             "units and result files (cancel a running job first)",
             [](SchedulerClient& client, const std::string& id) {
               const v1::DeleteJobResponse r = client.remove(id);
               fmt::print("job {} deleted, {} of files freed\n", r.job_id(), describe_bytes(r.bytes_freed()));
             });

  auto p = std::make_shared<PriorityOptions>();
  CLI::App* priority = app.add_subcommand("priority", "Change a job's priority: higher runs first (from its next unit on)");
  add_job_on_scheduler_options(*priority, p->target);
  priority->add_option("priority", p->priority, "The new priority (above the scheduler's --max-priority needs the admin role)")
      ->required();
  commands.add(priority, [p] {
    SchedulerClient client(resolve_scheduler_connection(p->target.scheduler));
    print_state(client.set_priority(client.resolve_job_id(p->target.job_id), p->priority), "");
    return 0;
  });

  auto l = std::make_shared<LimitsOptions>();
  CLI::App* limits = app.add_subcommand(
      "limits", "Change a job's caps while it runs: how many workers, and how many of its units, it may hold at once");
  add_job_on_scheduler_options(*limits, l->target);
  limits->add_option("--max-workers", l->max_workers, "At most this many workers at once (0: no cap)")
      ->check(CLI::Range(0, kMaxJobCap));
  limits->add_option("--max-units-in-flight", l->max_units_in_flight, "At most this many units out at once (0: no cap)")
      ->check(CLI::Range(0, kMaxJobCap));
  commands.add(limits, [l] {
    SchedulerClient client(resolve_scheduler_connection(l->target.scheduler));
    const v1::Job job = client.set_limits(client.resolve_job_id(l->target.job_id), l->max_workers, l->max_units_in_flight);
    print_state(job, caps_of(job));
    return 0;
  });

  auto d = std::make_shared<DependOptions>();
  CLI::App* depend = app.add_subcommand(
      "depend", "Make a job that has not started wait for other jobs too (as farm submit --after / --after-any)");
  add_job_on_scheduler_options(*depend, d->target);
  depend->add_option("--after", d->after, "Jobs it waits for to succeed (comma-separated ids or unique starts)")
      ->delimiter(',');
  depend->add_option("--after-any", d->after_any, "Jobs it waits for to end, however they end")->delimiter(',');
  commands.add(depend, [d] {
    SchedulerClient client(resolve_scheduler_connection(d->target.scheduler));
    const v1::Job job = client.add_dependencies(client.resolve_job_id(d->target.job_id),
                                                client.resolve_job_ids(d->after), client.resolve_job_ids(d->after_any));
    print_state(job, describe_dependencies(job));
    return 0;
  });
}

}  // namespace farm
