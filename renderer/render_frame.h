#pragma once
// A whole frame in this process: split into tiles, rendered on a thread pool through the engine
// contract, pasted into one film. What the engine tests and benchmarks use; the farm (and
// `farm render`) render the same tiles through the scheduler.
#include <chrono>
#include <cstddef>
#include <functional>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/thread_pool.h"

namespace farm {

struct TileProgress {
  std::size_t tiles_done = 0;
  std::size_t tiles_total = 0;
};
using ProgressCallback = std::function<void(const TileProgress&)>;

// Row-major tiles of `tile_size` covering the image; the last row and column may be smaller.
std::vector<Rect> split_into_tiles(int width, int height, int tile_size);

// Where a frame's time went: the engine's per-frame set-up (prepare_frame), then the tiles.
struct FrameTimings {
  double setup_ms = 0.0;
  double total_ms = 0.0;
};

// Renders the whole frame on `pool` into `film` (resized to the image; its memory is reused when
// it is big enough, as a frame loop would). The result does not depend on tile size or thread
// count. With settings.pass -1 and a frame of several passes (pass_count), renders every pass
// and merges them in order with a PassAccumulator: the frame a farm merges from the same
// passes, bit for bit. With settings.pass >= 0, renders that pass alone (its own samples'
// image, unmerged). Throws InputError for a bad pass or pass_spp before rendering anything.
void render_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                  TileBuffer& film, const ProgressCallback& progress = {},
                  FrameTimings* timings = nullptr);

// The same on a pool of settings.threads threads, created for this render.
TileBuffer render_frame(const PreparedScene& scene, const RenderSettings& settings,
                        const ProgressCallback& progress = {}, FrameTimings* timings = nullptr);

}  // namespace farm
