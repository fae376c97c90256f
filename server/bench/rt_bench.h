#pragma once
// `farm bench rt`: our BVHs against Embree on the lab's models and the 100-cow grid: build time
// and ray throughput on 1 or more threads for coherent (primary) and incoherent rays, closest-hit
// and any-hit, side by side in one run; a closest hit as found (SceneIntersector::find_closest),
// not completed into a surface hit. Embree is timed twice: through the farm's adapter (an
// instance level) and called directly (embree_direct.h: one level, rtcIntersect1/rtcOccluded1),
// the anchor issue #37 measures against.
#include <cstdint>
#include <filesystem>
#include <vector>

namespace farm {

struct RtBenchOptions {
  std::filesystem::path assets;       // folder with dae/cow.dae, dae/bunny.dae, dae/CBbunny.dae
  std::vector<std::filesystem::path> models;  // when given, these instead of the lab's four scenes
  std::uint64_t rays = 1'000'000;     // per ray set
  std::uint64_t naive_rays = 20'000;  // `naive` tests every triangle: fewer rays, same Mrays/s
  std::vector<int> threads = {1};     // a table for each count
  int repeats = 3;                    // rounds over every subject; medians reported
};

void run_rt_bench(const RtBenchOptions& options);

}  // namespace farm
