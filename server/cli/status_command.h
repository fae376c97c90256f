#pragma once
// `farm status [ID]`: the scheduler's jobs as a table, or one job in detail.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm status` to `app` and its runner to `commands`.
void add_status_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
