#include "server/cli/scheduler_target.h"

namespace farm {

void add_scheduler_address_option(CLI::App& command, std::string& address) {
  command.add_option("--scheduler", address,
                     "Scheduler HOST:PORT (default: $FARM_SCHEDULER, else localhost:50051)");
}

void add_job_on_scheduler_options(CLI::App& command, JobOnScheduler& target) {
  command.add_option("id", target.job_id, "Job id")->required();
  add_scheduler_address_option(command, target.scheduler);
}

}  // namespace farm
