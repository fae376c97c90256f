#pragma once
// `farm validate JOB`: checks our acceleration structure against Embree on the job's scene (the
// check itself is renderer/accel/accel_validation.h, which the scheduler runs for
// validate.embree_rays).
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "renderer/accel/accel_validation.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/util/input_error.h"
#include "server/cli/command_table.h"

namespace farm {

struct ValidateCommandOptions {
  std::filesystem::path job_file;
  JobLoadOptions load;
  std::optional<std::string> accel;   // bvh, bvh-median or naive; default: the job's
  std::optional<std::uint64_t> rays;  // default: validate.embree_rays, else 100000
};

// Prints the comparison and returns the exit code: 0 when the hits agree within the tolerance,
// 1 when they do not. Throws InputError for bad input.
int run_validate_command(const ValidateCommandOptions& options);

// Adds `farm validate` to `app` and its runner to `commands`.
void add_validate_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
