#pragma once
// `farm health`: asks a scheduler or a worker the standard gRPC health question
// (grpc.health.v1.Health/Check) and exits 0 only when it answers SERVING. For the places that
// cannot speak gRPC themselves: a container's HEALTHCHECK, a Compose healthcheck, a script that
// waits for its scheduler (docs/architecture.md §9).
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm health` to `app` and its runner to `commands`.
void add_health_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
