#pragma once
// The job file argument and --asset-root, declared once for the commands that read a job
// (`farm render`, `validate`, `submit`, `info`).
#include <CLI/CLI.hpp>

#include <filesystem>

#include "renderer/job/job.h"

namespace farm {

// Adds --asset-root, bound to `load` (which must outlive the parse).
void add_asset_root_option(CLI::App& command, JobLoadOptions& load);

// Adds the required JOB argument (an existing file) and --asset-root.
void add_job_file_options(CLI::App& command, std::filesystem::path& job_file, JobLoadOptions& load);

}  // namespace farm
