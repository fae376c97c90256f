#pragma once
// `farm log ID`: a job's event log as the scheduler keeps it (state changes, unit failures with the
// worker and the reason, retries, merged frames, operator actions), one line an event.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm log` to `app` and its runner to `commands`.
void add_log_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
