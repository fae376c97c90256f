#include "server/cli/status_command.h"
#include "server/common/job_eta.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "renderer/util/input_error.h"
#include "renderer/util/utf8_text.h"
#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {
namespace {

struct StatusOptions {
  JobOnScheduler target;  // job_id empty: list
  std::string states;     // comma-separated state names
  std::string name;
  std::size_t limit = 50;
  bool json = false;
};

std::vector<v1::JobState> parse_states(const std::string& list) {
  std::vector<v1::JobState> out;
  std::istringstream in(list);
  for (std::string name; std::getline(in, name, ',');) {
    if (name.empty()) continue;
    const std::optional<v1::JobState> state = job_state_named(name);
    if (!state) throw InputError(fmt::format("--state: '{}' is not a job state ({})", name, kJobStateNames));
    out.push_back(*state);
  }
  return out;
}

// How long the job has run: from its start to its end, or to now while it runs; "-" before.
std::string duration_of(const v1::Job& job) {
  if (!job.has_started_at() || job.started_at().seconds() == 0) return "-";
  const double end = job.has_finished_at() && job.finished_at().seconds() > 0
                         ? static_cast<double>(job.finished_at().seconds()) + job.finished_at().nanos() * 1e-9
                         : std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return short_duration(end - (static_cast<double>(job.started_at().seconds()) + job.started_at().nanos() * 1e-9));
}

// "1m05s" left at the units' measured rate; "-" for a job not running or not measured yet.
std::string eta_of(const v1::Job& job) {
  const std::optional<std::chrono::seconds> eta = job_eta(job, std::chrono::system_clock::now());
  return eta ? short_duration(static_cast<double>(eta->count())) : "-";
}

// At most `n` characters (bytes of ASCII; a cut never splits a UTF-8 sequence), "..." when cut.
std::string clipped(const std::string& text, std::size_t n) {
  if (text.size() <= n) return text;
  return utf8_prefix(text, n - 3) + "...";
}

int run_status(StatusOptions& o) {
  SchedulerClient client(resolve_scheduler_connection(o.target.scheduler));
  if (!o.target.job_id.empty()) {
    const v1::Job job = client.get(client.resolve_job_id(o.target.job_id));
    if (o.json) {
      fmt::print("{}\n", json_of(job));
    } else {
      print_job(job);
    }
    return 0;
  }
  bool more = false;
  const std::vector<v1::Job> jobs = client.list({.states = parse_states(o.states), .name = o.name, .limit = o.limit}, &more);
  if (o.json) {
    print_json_array(jobs);
    return 0;
  }
  if (jobs.empty()) {
    fmt::print("no jobs on {}{}\n", client.address(), o.states.empty() && o.name.empty() ? "" : " match");
    return 0;
  }
  constexpr const char* kRow = "{:<16}  {:<20}  {:<9}  {:>3}  {:>20}  {:>8}  {:>8}  {:<19}  {}\n";
  const auto row = [](std::string line) {  // without the blanks an empty last column leaves
    while (line.size() > 1 && line[line.size() - 2] == ' ') line.erase(line.size() - 2, 1);
    fmt::print("{}", line);
  };
  row(fmt::format(kRow, "ID", "NAME", "STATE", "PRI", "PROGRESS", "DURATION", "ETA", "SUBMITTED", "FAILURE"));
  for (const v1::Job& job : jobs) {
    row(fmt::format(kRow, job.job_id(), clipped(job.name(), 20), state_label(job), job.priority(),
                    progress_of(job), duration_of(job), eta_of(job), local_time(job.submitted_at()),
                    clipped(job.failure_reason(), 60)));
  }
  if (more) fmt::print("(the newest {}; more match: --limit 0 lists them all)\n", jobs.size());
  return 0;
}

}  // namespace

void add_status_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<StatusOptions>();
  CLI::App* status = app.add_subcommand("status", "List the scheduler's jobs, or show one");
  status->add_option("id", o->target.job_id, "Job id, or any unique start of it (default: list jobs)");
  status->add_option("--state", o->states,
                     std::string("List only jobs in these states, comma-separated: ") + kJobStateNames);
  status->add_option("--name", o->name, "List only jobs whose name matches this glob (* and ?; case-insensitive)");
  status->add_option("--limit", o->limit, "List at most the newest N (0 = all)")->capture_default_str();
  status->add_flag("--json", o->json, "Print the job, or the list, as JSON (the fields of farm.v1.Job)");
  add_scheduler_connection_options(*status, o->target.scheduler);
  commands.add(status, [o] { return run_status(*o); });
}

}  // namespace farm
