#pragma once
// The operator's actions on one job: `farm cancel`, `pause`, `resume`, `priority`, `retry`,
// `delete`, `limits` (its caps) and `depend` (more jobs to wait for), each taking a job id or any
// unique start of one.
#include "server/cli/command_table.h"

namespace farm {

// Adds the commands to `app` and their runners to `commands`.
void add_job_action_commands(CLI::App& app, CommandTable& commands);

}  // namespace farm
