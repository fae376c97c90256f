#pragma once
// Command-line values that replace a job's own (`farm render`, `farm submit`).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "renderer/job/job.h"

namespace farm {

struct RenderOverrides {
  std::optional<std::string> engine;
  std::optional<int> width, height, spp, threads, tile_size, max_depth;
  std::optional<std::uint64_t> seed;
  std::vector<std::string> add_aovs;  // AOV names the output gains (a regression z-test's variance)
  std::optional<std::filesystem::path> image, preview;  // preview "" = none
  std::optional<std::filesystem::path> video;           // "" = none
  bool full_float = false;                              // 32-bit EXR instead of half
  std::optional<int> show_bvh;  // draw BVH boxes of levels <= this over the preview
  // Frames of the job's range to render ("10-20" or "5"): written as frames.only.
  std::optional<std::pair<int, int>> frames;
};

// Applies overrides to a loaded job; throws InputError naming the option for a bad value (a
// --frames outside the job's range, or of a job without one; an --out without '#' for a job
// with frames; a --video of a still, of a type ffmpeg is not asked to make, or one whose previews
// --preview none turns off).
void apply_overrides(Job& job, const RenderOverrides& overrides);

}  // namespace farm
