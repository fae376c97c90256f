#pragma once
// `farm workers`: the scheduler's workers, their state and what they render.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm workers` to `app` and its runner to `commands`.
void add_workers_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
