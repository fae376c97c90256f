#pragma once
// `farm bench frames`: what a frame range costs beyond its frames, side by side in one run.
//   turntable  the lab's cow turning over 48 frames at 640x480 (raster, 1 thread): the whole
//              `farm render` command (process start to exit) against the engine's 48 frames plus
//              one model load, measured in this process. Per-frame reloading or full BVH rebuilds
//              would show as a ratio well above 1.
//   path       a 16-frame path-traced animation (jobs/moving_light.json) through a scheduler and
//              one worker, and through the scheduler and two workers over loopback: sharing the
//              machine's cores (half each, as many threads in all as the one worker has), and
//              each with every core.
#include <filesystem>
#include <string>

namespace farm {

struct FramesBenchOptions {
  std::filesystem::path cow = "../shared/assets/dae/cow.dae";
  std::filesystem::path path_job = "jobs/moving_light.json";
  int frames = 48;
  int repeats = 3;            // rounds; medians reported
  std::string scene = "all";  // turntable, path or all
};

void run_frames_bench(const FramesBenchOptions& options);

}  // namespace farm
