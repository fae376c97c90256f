#pragma once
// `farm bench path`: path tracer throughput on the project's Cornell box and the lab's CBbunny
// (lit by its ceiling lamp made emissive) at 512x512: Msamples/s and Mrays/s on one thread and on
// all of them; the textured Cornell box's cost per sample against the plain one's; the yard lit
// only by a sky map (jobs/environment.json); and, given a Python with Mitsuba 3, Mitsuba's
// scalar_rgb and its JIT variant llvm_ad_rgb (compiled in an untimed first render, whose time is
// printed) on the same Cornell box and sky-lit yard and thread counts in the same run, rendering in
// turns over --repeats rounds.
#include <filesystem>
#include <string>
#include <vector>

namespace farm {

struct PathBenchOptions {
  std::filesystem::path cornell_job = "jobs/cornell_path.json";
  std::filesystem::path textured_job = "jobs/cornell_textured.json";  // the same room, textured
  std::filesystem::path environment_job = "jobs/environment.json";    // lit by a sky map
  std::filesystem::path assets;       // the lab's assets; default ../shared/assets
  std::vector<int> threads;           // default: 1 and every hardware thread
  int width = 512, height = 512;
  int spp = 16;
  std::string scene = "all";          // cornell, textured (plain against textured), environment, cbbunny or all
  std::string mitsuba_python;         // a python with `mitsuba` installed; empty: skip Mitsuba
  std::filesystem::path mitsuba_script = "tools/mitsuba_reference.py";
  int repeats = 1;                    // rounds, farm and Mitsuba taking turns; medians reported
};

void run_path_bench(const PathBenchOptions& options);

}  // namespace farm
