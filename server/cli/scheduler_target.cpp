#include "server/cli/scheduler_target.h"

namespace farm {

void add_client_identity_options(CLI::App& command, SchedulerConnectionFlags& flags) {
  command.add_option("--token-file", flags.token_file,
                     "File whose first line is your farm token, sent with every call (default: "
                     "$FARM_TOKEN); a scheduler started with --tokens needs one");
  command.add_option("--tls-ca", flags.tls.ca,
                     "Talk TLS, verifying the scheduler's certificate against this CA (PEM) "
                     "(default: $FARM_TLS_CA)");
  command.add_option("--tls-cert", flags.tls.cert,
                     "Client certificate (PEM) for a scheduler that requires one (mTLS) "
                     "(default: $FARM_TLS_CERT)");
  command.add_option("--tls-key", flags.tls.key,
                     "Private key of --tls-cert (PEM) (default: $FARM_TLS_KEY)");
}

void add_scheduler_connection_options(CLI::App& command, SchedulerConnectionFlags& flags) {
  command.add_option("--scheduler", flags.address,
                     "Scheduler HOST:PORT (default: $FARM_SCHEDULER, else localhost:50051)");
  add_client_identity_options(command, flags);
}

std::optional<SchedulerConnection> resolve_optional_scheduler(const std::optional<std::string>& address,
                                                              const SchedulerConnectionFlags& identity) {
  if (!address) return std::nullopt;
  SchedulerConnectionFlags flags = identity;
  flags.address = *address;
  return resolve_scheduler_connection(flags);
}

void add_job_on_scheduler_options(CLI::App& command, JobOnScheduler& target) {
  command.add_option("id", target.job_id, "Job id, or any unique start of it")->required();
  add_scheduler_connection_options(command, target.scheduler);
}

}  // namespace farm
