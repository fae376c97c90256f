#include "server/bench/raster_bench.h"

#include <fmt/format.h>

#include <algorithm>

#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_scenes.h"
#include "server/bench/bench_support.h"

namespace farm {
namespace {

using bench::median;

struct Measurement {
  int threads = 0;
  double frame_ms = 0.0, setup_ms = 0.0;  // medians
  std::uint64_t fragments = 0;
};

Measurement measure(const Scene& scene, const RenderSettings& settings, int threads, int warmup,
                    int frames) {
  ThreadPool pool(threads);  // once per configuration, outside the timed frames
  TileBuffer film;           // reused by every frame, as in a frame loop
  std::vector<double> totals, setups;
  Measurement m;
  m.threads = threads;
  for (int i = 0; i < warmup + frames; ++i) {
    // A fresh prepared scene per frame, so the per-frame set-up is never served from a cache.
    const PreparedScene prepared{Scene(scene)};
    FrameTimings timings;
    render_frame(prepared, settings, pool, film, {}, &timings);
    if (i < warmup) continue;
    totals.push_back(timings.total_ms);
    setups.push_back(timings.setup_ms);
    m.fragments = film.stats().fragments;
  }
  m.frame_ms = median(totals);
  m.setup_ms = median(setups);
  return m;
}

void bench_scene(const std::string& name, const Scene& scene, const RasterBenchOptions& o) {
  RenderSettings settings;
  settings.engine = EngineKind::Raster;
  settings.width = o.width;
  settings.height = o.height;
  settings.tile_size = o.tile_size;
  const double triangles = static_cast<double>(scene.triangle_count());
  const int cores = resolve_thread_count(0);

  fmt::print("\nscene {}: {} triangles, {}x{}, tiles of {} px, median of {} frames after {} "
             "warm-up\n",
             name, scene.triangle_count(), o.width, o.height, o.tile_size, o.frames, o.warmup);
  fmt::print("{:>7} {:>10} {:>8} {:>10} {:>9} {:>13} {:>8} {:>8}\n", "threads", "frame ms",
             "speedup", "efficiency", "setup ms", "setup Mtri/s", "Mtri/s", "Mfrag/s");
  double single_ms = 0.0;
  for (int threads : o.threads) {
    if (threads > cores && !o.oversubscribe) {
      fmt::print("{:>7} skipped: {} cores here (--oversubscribe runs it anyway)\n", threads, cores);
      continue;
    }
    const Measurement m = measure(scene, settings, threads, o.warmup, o.frames);
    if (threads == 1) single_ms = m.frame_ms;
    const double speedup = single_ms > 0.0 ? single_ms / m.frame_ms : 0.0;
    fmt::print("{:>7} {:>10.2f} {:>7.2f}x {:>9.0f}% {:>9.2f} {:>13.1f} {:>8.1f} {:>8.1f}\n", threads,
               m.frame_ms, speedup, 100.0 * speedup / threads, m.setup_ms,
               triangles / (m.setup_ms * 1e3), triangles / (m.frame_ms * 1e3),
               static_cast<double>(m.fragments) / (m.frame_ms * 1e3));
  }
}

}  // namespace

void run_raster_bench(const RasterBenchOptions& options) {
  const std::filesystem::path model_path =
      options.model.empty() ? bench::default_cow_path() : options.model;
  if (!std::filesystem::exists(model_path)) {
    throw InputError(fmt::format("{}: no such model (pass --model PATH to the lab's cow.dae)",
                                 model_path.string()));
  }
  const auto cow = std::make_shared<const Model>(load_model(model_path));
  fmt::print("farm bench raster ({}), model {}\n", bench::machine_summary(), model_path.string());
  if (options.scene == "all" || options.scene == "cow") bench_scene("cow", bench::single_cow(cow), options);
  if (options.scene == "all" || options.scene == "cow-grid-100") {
    bench_scene("cow-grid-100", bench::cow_grid(cow, 10), options);
  }
}

}  // namespace farm
