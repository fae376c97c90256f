#pragma once
// Which scheduler, and which job on it, a client command talks to: --scheduler and the job id,
// declared once for `farm submit`, `status`, `watch`, `cancel` and `fetch`. The address is
// resolved by resolve_scheduler_address (server/client/scheduler_client.h).
#include <CLI/CLI.hpp>

#include <string>

namespace farm {

struct JobOnScheduler {
  std::string scheduler;  // empty: $FARM_SCHEDULER, else the default
  std::string job_id;
};

// Adds --scheduler HOST:PORT, bound to `address` (which must outlive the parse).
void add_scheduler_address_option(CLI::App& command, std::string& address);

// Adds the required job ID argument and --scheduler.
void add_job_on_scheduler_options(CLI::App& command, JobOnScheduler& target);

}  // namespace farm
