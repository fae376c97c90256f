#include "renderer/render_frame.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

#include "renderer/engine.h"
#include "renderer/image/pass_merge.h"
#include "renderer/util/thread_pool.h"

namespace farm {

std::vector<Rect> split_into_tiles(int width, int height, int tile_size) {
  std::vector<Rect> tiles;
  for (int y = 0; y < height; y += tile_size) {
    for (int x = 0; x < width; x += tile_size) {
      tiles.push_back({x, y, std::min(x + tile_size, width), std::min(y + tile_size, height)});
    }
  }
  return tiles;
}

TileBuffer render_frame(const PreparedScene& scene, const RenderSettings& settings,
                        const ProgressCallback& progress, FrameTimings* timings) {
  ThreadPool pool(resolve_thread_count(settings.threads));
  TileBuffer film;
  render_frame(scene, settings, pool, film, progress, timings);
  return film;
}

namespace {

// The tiles of one render (all samples, or one pass) on `pool`, pasted into `film`.
void render_tiles(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                  const std::vector<Rect>& tiles, TileBuffer& film, const ProgressCallback& progress,
                  std::size_t& done, std::size_t total) {
  // The tiles cover the film exactly, so it need not be cleared first.
  film.reset_for_overwrite(Rect{0, 0, settings.width, settings.height}, settings.aovs);
  // Tiles are handed out one at a time; each worker renders into its own buffer and copies the
  // finished tile into the film. Tiles are disjoint, so the copies need no lock; only the
  // counters and the progress callback do.
  // Each worker's buffer and counters on cache lines of their own: an engine counts into its
  // buffer's stats every sample, and a neighbour's line shared with them would bounce between
  // the cores on every count.
  struct alignas(128) WorkerScratch {
    TileBuffer tile;
    RenderStats stats;
  };
  std::vector<WorkerScratch> scratch(static_cast<std::size_t>(pool.size()));
  std::mutex progress_mutex;
  pool.parallel_for(tiles.size(), 1, [&](std::size_t begin, std::size_t end, int worker) {
    WorkerScratch& own = scratch[static_cast<std::size_t>(worker)];
    TileBuffer& tile = own.tile;
    for (std::size_t i = begin; i < end; ++i) {
      render_tile(scene, settings, tiles[i], tile);
      film.paste(tile);
      own.stats += tile.stats();
      if (!progress) continue;
      std::lock_guard lock(progress_mutex);
      progress({++done, total});
    }
  });
  for (const WorkerScratch& s : scratch) film.stats() += s.stats;
}

}  // namespace

void render_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                  TileBuffer& film, const ProgressCallback& progress, FrameTimings* timings) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  static_cast<void>(samples_to_render(settings));  // a bad pass or pass_spp, before any work
  const Rect image{0, 0, settings.width, settings.height};
  const std::vector<Rect> tiles = split_into_tiles(settings.width, settings.height,
                                                   settings.tile_size);
  // One pool for the whole render: the engine's per-frame set-up and then the tiles.
  prepare_frame(scene, settings, pool);
  const Clock::time_point set_up = Clock::now();

  // Pass -1 of a frame split into passes renders each pass and merges them as a farm does, so
  // that the frame is bit for bit the one a farm merges from the same passes.
  const int passes = settings.pass == -1 ? pass_count(settings) : 1;
  const std::size_t total = tiles.size() * static_cast<std::size_t>(passes);
  std::size_t done = 0;
  if (passes == 1) {
    render_tiles(scene, settings, pool, tiles, film, progress, done, total);
  } else {
    PassAccumulator merged(image, settings.aovs);
    TileBuffer pass_film;
    RenderSettings pass_settings = settings;
    for (int p = 0; p < passes; ++p) {
      pass_settings.pass = p;
      render_tiles(scene, pass_settings, pool, tiles, pass_film, progress, done, total);
      merged.add(pass_film, pass_samples(settings, p));
    }
    merged.resolve(film);
  }
  if (timings) {
    const auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
    timings->setup_ms = ms(set_up - start);
    timings->total_ms = ms(Clock::now() - start);
  }
}

}  // namespace farm
