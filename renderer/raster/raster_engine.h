#pragma once
// The software rasterizer, sort-middle: once per frame the vertex stage, triangle set-up and
// binning (raster_frame.h); per tile, each bin it overlaps is rasterized (edge functions with a
// top-left fill rule on a fixed-point grid, perspective-correct interpolation, z-buffer) and
// then shaded with Blinn-Phong (renderer/scene/blinn_phong.h), with no shared mutable state.
#include <cstdint>
#include <memory>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/raster/raster_frame.h"
#include "renderer/util/cancel_flag.h"
#include "renderer/util/thread_pool.h"

namespace farm::raster {

// Builds the frame set-up on `pool` and caches it in the prepared scene for the tiles that follow.
void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                   const CancelFlag& cancel);

// Renders one tile; uses the cached frame set-up, building it on this thread if missing. Polls
// `cancel` every few hundred triangles drawn and at every sample pass over a bin; see
// farm::render_tile for what a stopped render leaves.
StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel);

// Renders one tile from an explicit frame set-up (benchmarks time the two halves separately).
StopReason render_tile_from_frame(const RasterFrame& frame, const PreparedScene& scene,
                                  const RenderSettings& settings, const Rect& requested,
                                  TileBuffer& out, const CancelFlag& cancel = CancelFlag::never());

}  // namespace farm::raster
