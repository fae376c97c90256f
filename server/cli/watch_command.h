#pragma once
// `farm watch ID`: follows a job to its end; the exit code says how it ended.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm watch` to `app` and its runner to `commands`.
void add_watch_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
