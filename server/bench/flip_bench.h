#pragma once
// `farm bench flip`: `farm compare --metric flip` against NVIDIA's flip-evaluator (PyPI) on the
// same 1920x1080 pair (LDR: PNG previews; HDR: half EXRs) and thread count, whole commands
// (process start to exit), taking turns, medians.
#include <filesystem>
#include <string>
#include <vector>

namespace farm {

struct FlipBenchOptions {
  std::filesystem::path job = "jobs/cornell.json";  // rendered at 4 spp (reference) and 1 spp (new)
  int width = 1920, height = 1080;
  std::vector<int> threads = {1, 2};
  int repeats = 5;
  std::string python = "build/test-venv/bin/python";  // with flip-evaluator installed
};

void run_flip_bench(const FlipBenchOptions& options);

}  // namespace farm
