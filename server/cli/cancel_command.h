#pragma once
// `farm cancel ID`: cancels a job on the scheduler.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm cancel` to `app` and its runner to `commands`.
void add_cancel_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
