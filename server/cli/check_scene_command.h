#pragma once
// `farm check-scene JOB --asset-root DIR --memory-limit BYTES`: not for people. `farm scheduler`
// runs its own binary this way to load a submitted job's models under a memory and time budget
// (server/scheduler/jobs/scene_check.h); it is left out of `farm --help`.
#include "server/cli/command_table.h"

namespace farm {

void add_check_scene_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
