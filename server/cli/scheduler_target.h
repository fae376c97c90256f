#pragma once
// Which scheduler, and which job on it, a client command talks to, and how it proves who it is:
// --scheduler, --token-file, --tls-ca, --tls-cert, --tls-key and the job id, declared once for
// `farm submit`, `status`, `watch`, `cancel`, `fetch`, `regress` and `grade`. The values are
// resolved (environment, defaults) by resolve_scheduler_connection
// (server/client/scheduler_connection.h).
#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "server/client/scheduler_connection.h"

namespace farm {

struct JobOnScheduler {
  SchedulerConnectionFlags scheduler;
  std::string job_id;
};

// Adds --token-file, --tls-ca, --tls-cert and --tls-key, bound to `flags` (which must outlive the
// parse); not --scheduler.
void add_client_identity_options(CLI::App& command, SchedulerConnectionFlags& flags);

// Adds --scheduler HOST:PORT and the identity options above.
void add_scheduler_connection_options(CLI::App& command, SchedulerConnectionFlags& flags);

// `farm regress` and `farm grade` render on a scheduler only when --scheduler is given: its
// connection then, with the identity options; nullopt without it.
std::optional<SchedulerConnection> resolve_optional_scheduler(const std::optional<std::string>& address,
                                                              const SchedulerConnectionFlags& identity);

// Adds the required job ID argument and the connection options.
void add_job_on_scheduler_options(CLI::App& command, JobOnScheduler& target);

}  // namespace farm
