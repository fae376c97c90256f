#pragma once
// The embedded pipeline behind `farm render`: split the frame into tiles, render them on local
// worker threads through the engine contract, and merge them into one film.
#include <chrono>
#include <cstddef>
#include <functional>

#include "renderer/image/tile_buffer.h"
#include "renderer/prepared_scene.h"
#include "renderer/render_settings.h"

namespace farm {

struct TileProgress {
  std::size_t tiles_done = 0;
  std::size_t tiles_total = 0;
};
using ProgressCallback = std::function<void(const TileProgress&)>;

// Row-major tiles of `tile_size` covering the image; the last row and column may be smaller.
std::vector<Rect> split_into_tiles(int width, int height, int tile_size);

// Number of worker threads `threads` asks for (0 = all hardware threads).
int resolve_thread_count(int threads);

// Renders the whole frame. The result does not depend on tile size or thread count.
TileBuffer render_frame(const PreparedScene& scene, const RenderSettings& settings,
                        const ProgressCallback& progress = {});

}  // namespace farm
