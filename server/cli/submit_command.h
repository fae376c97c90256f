#pragma once
// `farm submit JOB`: sends a job and the assets the scheduler lacks (by SHA-256); with
// --wait, follows it and downloads the results to the job's output paths.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm submit` to `app` and its runner to `commands`.
void add_submit_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
