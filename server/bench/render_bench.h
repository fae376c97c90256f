#pragma once
// `farm bench render`: the whole `farm render` command, timed from process start to exit as a
// user times it, against the bare engine frame on the same scene, side by side: the lab's cow
// job (640x480 with AOVs and preview) and a 10 x 10 grid of that cow at 1920x1080, on 1 and 2
// threads. What the embedded pipeline costs beyond the engine is the difference.
#include <filesystem>
#include <string>
#include <vector>

namespace farm {

struct RenderBenchOptions {
  std::filesystem::path cow_job = "jobs/cow.json";
  std::filesystem::path asset_root = "../shared/assets";  // where the cow job's model lies
  std::vector<int> threads{1, 2};
  int repeats = 5;              // rounds; medians reported
  std::string scene = "all";    // cow, cow-grid-100 or all
};

void run_render_bench(const RenderBenchOptions& options);

}  // namespace farm
