#include "server/cli/health_command.h"

#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <string>

#include "server/cli/duration_option.h"
#include "server/cli/scheduler_target.h"
#include "server/common/client_identity.h"
#include "server/common/health_check.h"

namespace farm {

namespace {

struct HealthOptions {
  SchedulerConnectionFlags scheduler;
  std::string address;  // a worker's, or a scheduler's other than --scheduler
  std::string timeout = "5s";
};

const char* serving_status_name(int status) {
  switch (status) {
    case 1: return "SERVING";
    case 2: return "NOT_SERVING";
    case 3: return "SERVICE_UNKNOWN";
    default: return "UNKNOWN";
  }
}

int run_health(const HealthOptions& o) {
  SchedulerConnection connection = resolve_scheduler_connection(o.scheduler);
  if (!o.address.empty()) connection.address = o.address;
  const auto timeout = parse_duration(o.timeout, "--timeout");
  const auto deadline = std::chrono::system_clock::now() + timeout;
  const auto channel = open_channel(connection.address, connection.identity);
  const HealthCheck check = check_health(channel, deadline);
  if (!check.status.ok()) {
    fmt::print(stderr, "{}: no answer: {} ({})\n", connection.address, check.status.error_message(),
               static_cast<int>(check.status.error_code()));
    return 1;
  }
  fmt::print("{}: {}\n", connection.address, serving_status_name(check.serving_status));
  return check.serving() ? 0 : 1;
}

}  // namespace

void add_health_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<HealthOptions>();
  CLI::App* health = app.add_subcommand(
      "health", "Ask a scheduler (or, given its ADDRESS, a worker) whether it is serving, through the standard "
                "gRPC health service; exit 0 when SERVING, 1 otherwise (for container and Compose health checks)");
  health->add_option("address", o->address,
                     "HOST:PORT of the server to ask (a worker's, say); default: the --scheduler address");
  health->add_option("--timeout", o->timeout, "How long to wait for the answer (default 5s)");
  add_scheduler_connection_options(*health, o->scheduler);
  commands.add(health, [o] { return run_health(*o); });
}

}  // namespace farm
