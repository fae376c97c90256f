#include "server/cli/workers_command.h"
#include "server/common/job_eta.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <chrono>
#include <memory>
#include <string>

#include "server/cli/job_display.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"

namespace farm {

namespace {

struct WorkersOptions {
  SchedulerConnectionFlags scheduler;
  bool json = false;
};

std::string state_of(const v1::WorkerInfo& w) {
  switch (w.state()) {
    case v1::WORKER_STATE_UP: return "up";
    case v1::WORKER_STATE_DOWN: return "down";
    case v1::WORKER_STATE_QUARANTINED: return "quarantined";
    case v1::WORKER_STATE_BACKED_OFF: return "backed-off";
    case v1::WORKER_STATE_LOST: return "lost";
    default: return "unknown";
  }
}

// "0.4s ago", "3m05s ago".
std::string ago(const google::protobuf::Timestamp& t) {
  const double then = static_cast<double>(t.seconds()) + t.nanos() * 1e-9;
  const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  return short_duration(now - then) + " ago";
}

// "0.4s ago"; "-" for a worker that does not heartbeat (a static one).
std::string heartbeat_of(const v1::WorkerInfo& w) { return w.has_last_heartbeat() ? ago(w.last_heartbeat()) : "-"; }

int run_workers(const WorkersOptions& o) {
  SchedulerClient client(resolve_scheduler_connection(o.scheduler));
  const std::vector<v1::WorkerInfo> workers = client.workers();
  if (o.json) {
    print_json_array(workers);
    return 0;
  }
  if (workers.empty()) {
    fmt::print("no workers on {} (start one with farm worker --scheduler {})\n", client.address(), client.address());
    return 0;
  }
  constexpr const char* kRow = "{:<28}  {:<11}  {:>7}  {:<19}  {:>6}  {:>6}  {:>12}  {}\n";
  fmt::print(kRow, "ADDRESS", "STATE", "THREADS", "ENGINES", "DONE", "FAILED", "HEARTBEAT", "CURRENT");
  for (const v1::WorkerInfo& w : workers) {
    std::string engines;
    for (const std::string& e : w.engines()) engines += (engines.empty() ? "" : ",") + e;
    std::string current = w.current().empty() ? "-" : w.current(0);
    if (w.current_size() > 1) current += fmt::format(" (+{} more)", w.current_size() - 1);
    fmt::print(kRow, w.address(), state_of(w), w.threads() > 0 ? std::to_string(w.threads()) : "-",
               engines.empty() ? "-" : engines, w.units_done(), w.units_failed(), heartbeat_of(w), current);
    if (!w.tags().empty()) fmt::print("    tags: {}\n", fmt::join(w.tags(), ", "));
    if (!w.quarantine_reason().empty()) fmt::print("    quarantined: {}\n", w.quarantine_reason());
    if (w.state() == v1::WORKER_STATE_BACKED_OFF) {
      const double until = static_cast<double>(w.backed_off_until().seconds()) + w.backed_off_until().nanos() * 1e-9;
      const double now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      fmt::print("    backed off for {:.1f}s more: {}\n", std::max(0.0, until - now), w.back_off_reason());
    }
    for (const std::string& job : w.blocked_jobs()) fmt::print("    kept off job {}: it failed its units\n", job);
    if (w.state() == v1::WORKER_STATE_LOST) {
      fmt::print("    lost {}: {}\n", ago(w.lost_at()), w.lost_reason());
    }
  }
  return 0;
}

}  // namespace

void add_workers_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<WorkersOptions>();
  CLI::App* workers = app.add_subcommand(
      "workers", "List the scheduler's workers: address, state (up, down, backed-off, quarantined, lost), threads, "
                 "engines, units done and failed, last heartbeat, units rendering now, jobs it is kept off");
  workers->add_flag("--json", o->json, "Print the list as JSON (the fields of farm.v1.WorkerInfo)");
  add_scheduler_connection_options(*workers, o->scheduler);
  commands.add(workers, [o] { return run_workers(*o); });
}

}  // namespace farm
