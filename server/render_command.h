#pragma once
// `farm render JOB`: the whole pipeline in one process (load, prepare, render tiles on local
// threads, merge, write EXR and preview), with a progress bar and a timing summary.
#include <filesystem>
#include <optional>
#include <string>

#include "renderer/scene/job.h"

namespace farm {

// Command-line values that replace the job's.
struct RenderOverrides {
  std::optional<std::string> engine;
  std::optional<int> width, height, spp, threads, tile_size;
  std::optional<std::filesystem::path> image, preview;  // preview "" = none
  bool full_float = false;                              // 32-bit EXR instead of half
  std::optional<int> show_bvh;  // draw BVH boxes of levels <= this over the preview
};

struct RenderCommandOptions {
  std::filesystem::path job_file;
  JobLoadOptions load;
  RenderOverrides overrides;
  bool progress = true;  // drawn only on a terminal anyway
};

// Applies overrides to a loaded job; throws InputError naming the option for a bad value.
void apply_overrides(Job& job, const RenderOverrides& overrides);

// Runs the render and prints where the files went and how long each stage took. Throws
// InputError for bad input (exit code 2) and other exceptions for internal failures.
void run_render_command(const RenderCommandOptions& options);

}  // namespace farm
