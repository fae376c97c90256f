#pragma once
// `farm bench rt`: our BVHs against Embree on the lab's models and the 100-cow grid: build time
// and single-thread ray throughput for coherent (primary) and incoherent rays, closest-hit and
// any-hit, side by side in one run.
#include <cstdint>
#include <filesystem>

namespace farm {

struct RtBenchOptions {
  std::filesystem::path assets;       // folder with dae/cow.dae, dae/bunny.dae, dae/CBbunny.dae
  std::uint64_t rays = 1'000'000;     // per ray set
  std::uint64_t naive_rays = 20'000;  // `naive` tests every triangle: fewer rays, same Mrays/s
};

void run_rt_bench(const RtBenchOptions& options);

}  // namespace farm
