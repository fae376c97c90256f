#include "renderer/render_frame.h"

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

#include "renderer/engine.h"
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

void render_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                  TileBuffer& film, const ProgressCallback& progress, FrameTimings* timings) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  // The tiles cover the film exactly, so it need not be cleared first.
  film.reset_for_overwrite(Rect{0, 0, settings.width, settings.height}, settings.aovs);
  const std::vector<Rect> tiles = split_into_tiles(settings.width, settings.height,
                                                   settings.tile_size);
  // One pool for the whole render: the engine's per-frame set-up and then the tiles.
  prepare_frame(scene, settings, pool);
  const Clock::time_point set_up = Clock::now();

  // Tiles are handed out one at a time; each worker renders into its own buffer and copies the
  // finished tile into the film. Tiles are disjoint, so the copies need no lock; only the
  // counters and the progress callback do.
  std::vector<TileBuffer> scratch(static_cast<std::size_t>(pool.size()));
  std::vector<RenderStats> stats(scratch.size());
  std::mutex progress_mutex;
  std::size_t done = 0;
  pool.parallel_for(tiles.size(), 1, [&](std::size_t begin, std::size_t end, int worker) {
    TileBuffer& tile = scratch[static_cast<std::size_t>(worker)];
    for (std::size_t i = begin; i < end; ++i) {
      render_tile(scene, settings, tiles[i], tile);
      film.paste(tile);
      stats[static_cast<std::size_t>(worker)] += tile.stats();
      if (!progress) continue;
      std::lock_guard lock(progress_mutex);
      progress({++done, tiles.size()});
    }
  });
  for (const RenderStats& s : stats) film.stats() += s;
  if (timings) {
    const auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
    timings->setup_ms = ms(set_up - start);
    timings->total_ms = ms(Clock::now() - start);
  }
}

}  // namespace farm
