#pragma once
// `farm info FILE`: what a model file or a job file contains, without rendering.
#include <filesystem>

#include "renderer/job/job.h"
#include "server/cli/command_table.h"

namespace farm {

void run_info_command(const std::filesystem::path& file, const JobLoadOptions& load);

// Adds `farm info` to `app` and its runner to `commands`.
void add_info_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
