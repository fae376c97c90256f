#pragma once
// `--log-level NAME` for the commands that run farm services (render's embedded farm, worker,
// scheduler): the operator's level for every logger in the process (server/common/log.h).
#include <CLI/CLI.hpp>

namespace farm {

// `default_level` only documents the command's own default in --help.
void add_log_level_option(CLI::App& command, const char* default_level);

}  // namespace farm
