#include "server/local_pipeline.h"

#include <algorithm>
#include <mutex>
#include <thread>

#include "renderer/engine.h"
#include "renderer/thread_pool.h"

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

int resolve_thread_count(int threads) {
  if (threads > 0) return threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

TileBuffer render_frame(const PreparedScene& scene, const RenderSettings& settings,
                        const ProgressCallback& progress) {
  TileBuffer film(Rect{0, 0, settings.width, settings.height}, settings.aovs);
  const std::vector<Rect> tiles = split_into_tiles(settings.width, settings.height,
                                                   settings.tile_size);
  // One pool for the whole render: the engine's per-frame set-up and then the tiles.
  ThreadPool pool(resolve_thread_count(settings.threads));
  prepare_frame(scene, settings, pool);

  // Tiles are handed out one at a time; each worker renders into its own buffer and pastes the
  // finished tile under the lock, so the film only ever sees whole tiles.
  std::vector<TileBuffer> scratch(static_cast<std::size_t>(pool.size()));
  std::mutex merge_mutex;
  std::size_t done = 0;
  pool.parallel_for(tiles.size(), 1, [&](std::size_t begin, std::size_t end, int worker) {
    TileBuffer& tile = scratch[static_cast<std::size_t>(worker)];
    for (std::size_t i = begin; i < end; ++i) {
      render_tile(scene, settings, tiles[i], tile);
      std::lock_guard lock(merge_mutex);
      film.paste(tile);
      ++done;
      if (progress) progress({done, tiles.size()});
    }
  });
  return film;
}

}  // namespace farm
