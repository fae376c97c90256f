#pragma once
// `farm render JOB`: the whole pipeline in one process (load, prepare, render tiles on local
// threads, merge, write EXR and preview), with a progress bar and a timing summary.
#include <filesystem>
#include <optional>
#include <string>

#include "renderer/job/job.h"
#include "server/cli/command_table.h"
#include "server/client/render_overrides.h"

namespace farm {

struct RenderCommandOptions {
  std::filesystem::path job_file;
  JobLoadOptions load;
  RenderOverrides overrides;
  bool progress = true;  // drawn only on a terminal anyway
};

// Runs the render and prints where the files went and how long each stage took, then ends the
// process with exit code 0 (exit_abandoning_calls, server_shutdown.h): it does not return on success. Throws
// InputError for bad input (exit code 2) and other exceptions for internal failures.
[[noreturn]] void run_render_command(const RenderCommandOptions& options);

// Adds `farm render` to `app` and its runner to `commands`.
void add_render_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
