#pragma once
// The one entry point every engine implements (docs/architecture.md, "The engine contract"):
//   render_tile(prepared scene, settings, tile rectangle, output buffer[, cancel flag])
// A pure function of its inputs: a pixel's value never depends on tiling or threads, nor on
// whether a cancel flag was passed (one that never stops the render changes no bit).
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/cancel_flag.h"
#include "renderer/util/thread_pool.h"

namespace farm {

// Optional: does the per-frame work an engine shares between tiles (the rasterizer's vertex
// stage, set-up and binning) on `pool`, before tiles are dispatched. render_tile does it lazily
// on its own thread when this was not called. Polls `cancel` as it goes (every few hundred
// triangles or BVH primitives) and throws RenderStopped when it asks: set-up that grows with
// the scene and the resolution stops as promptly as a tile does.
void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                   const CancelFlag& cancel = CancelFlag::never());

// Renders `tile` (clipped to the image) into `out`, which it resizes to the tile and the
// settings' AOVs. Renders the samples of settings.pass (all of them for pass -1; see
// samples_to_render): a pass's buffer is an image of its own samples only, which
// PassAccumulator merges with the frame's other passes. Throws InputError for an engine this
// build cannot run, a negative pass_spp, or a pass out of range (pass_count).
void render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out);

// The same, stopping early when `cancel` asks: every engine polls it every few samples (ray
// engines) or triangles and bin passes (rasterizer), so it stops within milliseconds whatever the
// spp or the tile size. Returns StopReason::None when the tile is complete; otherwise why it
// stopped, with `out` holding no pixels (discard_pixels(): only the stats of the work done).
[[nodiscard]] StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings,
                                     const Rect& tile, TileBuffer& out, const CancelFlag& cancel);

}  // namespace farm
