#pragma once
// `farm fetch ID`: downloads a finished job's EXR and preview.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm fetch` to `app` and its runner to `commands`.
void add_fetch_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
