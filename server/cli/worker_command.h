#pragma once
// `farm worker`: serves farm.v1.Worker, gRPC health and server reflection until SIGINT/SIGTERM.
#include "server/cli/command_table.h"
#include "server/common/server_security.h"
#include "server/worker/worker_service.h"

namespace farm {

struct WorkerCommandOptions {
  WorkerOptions worker;
  ServerSecurityOptions security;
};

// Prints "worker listening on HOST:PORT" (the port chosen when ADDR asked for port 0) once the
// server accepts calls. InputError when the address cannot be bound. Returns the exit code.
int run_worker_command(const WorkerCommandOptions& options);

// Adds `farm worker` to `app` and its runner to `commands`.
void add_worker_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
