#include "server/local_pipeline.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

#include "renderer/engine.h"

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
  return std::max(1u, std::thread::hardware_concurrency());
}

TileBuffer render_frame(const PreparedScene& scene, const RenderSettings& settings,
                        const ProgressCallback& progress) {
  TileBuffer film(Rect{0, 0, settings.width, settings.height}, settings.aovs);
  const std::vector<Rect> tiles = split_into_tiles(settings.width, settings.height,
                                                   settings.tile_size);
  const int workers = std::min<int>(resolve_thread_count(settings.threads),
                                    static_cast<int>(tiles.size()));

  // Tiles are handed out dynamically; each worker pastes its finished tile under the lock, so
  // the film sees whole tiles and the progress callback runs on one thread at a time.
  std::atomic<std::size_t> next{0};
  std::mutex merge_mutex;
  std::size_t done = 0;
  std::exception_ptr failure;

  auto work = [&] {
    TileBuffer tile;
    for (std::size_t i = next++; i < tiles.size(); i = next++) {
      try {
        render_tile(scene, settings, tiles[i], tile);
      } catch (...) {
        std::lock_guard lock(merge_mutex);
        if (!failure) failure = std::current_exception();
        next = tiles.size();
        return;
      }
      std::lock_guard lock(merge_mutex);
      film.paste(tile);
      ++done;
      if (progress) progress({done, tiles.size()});
    }
  };

  std::vector<std::thread> pool;
  for (int i = 1; i < workers; ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return film;
}

}  // namespace farm
