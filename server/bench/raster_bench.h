#pragma once
// `farm bench raster`: how fast the rasterizer renders the single cow and the 100-cow grid at
// 1920x1080 on 1, 2, 4, 8, 16 threads, and how well it scales.
#include <filesystem>
#include <string>
#include <vector>

namespace farm {

struct RasterBenchOptions {
  std::filesystem::path model;                // the cow; default bench::default_cow_path()
  std::vector<int> threads{1, 2, 4, 8, 16};
  int frames = 5;                             // timed frames per configuration (median reported)
  int warmup = 1;
  bool oversubscribe = false;                 // run thread counts above the core count too
  int width = 1920, height = 1080;
  int tile_size = 32;
  std::string scene = "all";                 // cow, cow-grid-100 or all
};

void run_raster_bench(const RasterBenchOptions& options);

}  // namespace farm
