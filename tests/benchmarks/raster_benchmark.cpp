// Google Benchmark view of `farm bench raster`: whole rasterizer frames (set-up, tiles, merge)
// for the single cow and the 100-cow grid at 1920x1080, one benchmark per thread count up to the
// number of cores. Run: build/release/tests/farm_raster_benchmark [--benchmark_repetitions=5]
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>

#include "renderer/render_frame.h"
#include "renderer/scene/model.h"
#include "server/bench/bench_scenes.h"

namespace {

using namespace farm;

void raster_frame(benchmark::State& state, const Scene* scene) {
  RenderSettings settings;
  settings.width = 1920;
  settings.height = 1080;
  ThreadPool pool(static_cast<int>(state.range(0)));
  TileBuffer film;
  for (auto _ : state) {
    const PreparedScene prepared{Scene(*scene)};  // no frame set-up cached between iterations
    render_frame(prepared, settings, pool, film);
    benchmark::DoNotOptimize(film.rgba(0, 0));
    state.counters["fragments"] = static_cast<double>(film.stats().fragments);
  }
  state.counters["Mtri/s"] = benchmark::Counter(
      static_cast<double>(scene->triangle_count()) * static_cast<double>(state.iterations()) / 1e6,
      benchmark::Counter::kIsRate);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  const char* env = std::getenv("FARM_COW");
  const std::filesystem::path cow_path = env ? env : FARM_SHARED_ASSETS "/dae/cow.dae";
  if (!std::filesystem::exists(cow_path)) {
    std::fprintf(stderr, "no cow model at %s (set FARM_COW)\n", cow_path.c_str());
    return 2;
  }
  const auto cow = std::make_shared<const Model>(load_model(cow_path));
  static const Scene single = bench::single_cow(cow);
  static const Scene grid = bench::cow_grid(cow, 10);
  const int cores = farm::resolve_thread_count(0);
  for (const auto& [name, scene] : {std::pair{"raster/cow", &single}, std::pair{"raster/cow-grid-100", &grid}}) {
    auto* b = benchmark::RegisterBenchmark(name, raster_frame, scene);
    for (int threads : {1, 2, 4, 8, 16}) {
      if (threads <= cores) b->Arg(threads);
    }
    b->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
