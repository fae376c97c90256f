#pragma once
// `farm scheduler`: serves farm.v1.Scheduler (SchedulerCore over gRPC), gRPC health and server
// reflection until SIGINT/SIGTERM.
#include <filesystem>
#include <string>
#include <vector>

#include "server/cli/command_table.h"
#include "server/common/listen_policy.h"
#include "server/common/server_security.h"
#include "server/scheduler/options/submit_limits.h"

namespace farm {

struct SchedulerCommandOptions {
  std::string listen = kDefaultSchedulerListen;  // host:port; port 0 = any free port
  std::filesystem::path data_dir;     // jobs.db, assets/, tiles/, results/
  std::string store;                  // a postgresql:// URL; empty: SQLite, data_dir/jobs.db
  double lease_s = 10;                // SchedulerOptions::lease
  std::vector<std::string> workers;   // static `farm worker` addresses
  double tile_deadline_s = 600;
  int max_attempts = 3;
  double upload_idle_timeout_s = 30;  // SchedulerOptions::upload_idle_timeout
  std::string keep_finished;          // a duration (duration_option.h); empty: for ever
  std::string http;                   // the dashboard's HOST:PORT; empty: none
  std::vector<std::string> http_hosts;  // --http-host: more names the dashboard answers to
  std::string notify_url;             // the webhook a job's end is posted to; empty: none
  int max_lost_worker_attempts = 10;  // SchedulerOptions::max_lost_worker_attempts
  int tiles_per_worker = 2;
  int batch_ms = 200;
  double heartbeat_interval_s = 1;
  bool float_exr = false;
  double verify_fraction = 0;  // SchedulerOptions::verify_fraction
  double remote_verify_fraction = 0.02;  // SchedulerOptions::remote_verify_fraction
  ServerSecurityOptions security;
  int max_priority = 100;             // above this needs the admin role
  SubmitLimits limits;                // SchedulerOptions::limits
};

// Prints "scheduler listening on HOST:PORT" once it accepts calls. InputError when the address
// cannot be bound. Returns the exit code.
int run_scheduler_command(const SchedulerCommandOptions& options);

// Adds `farm scheduler` to `app` and its runner to `commands`.
void add_scheduler_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
