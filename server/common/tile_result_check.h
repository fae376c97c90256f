#pragma once
// What a worker's reply must be before anything of it is kept. A worker is a process on another
// machine, so its reply is checked like any other input: the rectangle asked for, the planes the
// job asks for and no others, each the right size, and only values an engine can write
// (docs/architecture.md, "The engine contract"):
//
//   rgba      finite; A (coverage) in [0, 1], and for one sample a pixel 0 or 1 as its depth says
//             (every engine drops a NaN or infinite sample before it reaches the pixel)
//   depth     positive, +inf where nothing was hit; never NaN or negative
//   normal    unit length (within 1e-3), zero exactly where nothing was hit
//   albedo    finite, zero where nothing was hit
//   bvh_cost  a whole number >= 0 from whitted; 0 from raster and path, which do not count
//   variance  finite >= 0 from path; 0 from raster and whitted, whose pixels are no estimates
//   stats     times finite and >= 0; path samples = pixels x the pass's samples (spp without
//             passes; settings.pass says which), none from the other engines
//
// The scheduler checks every reply that crossed the wire (server/scheduler/dispatch/dispatcher.cpp); the
// unit tests render real tiles with every engine and AOV to show that honest replies pass.
#include <string>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"

namespace farm {

// Why `reply` cannot be what a worker renders for the rectangle `asked` of a frame rendered with
// `settings` (one sentence naming the plane, the pixel and the value); empty when it can be.
std::string check_tile_reply(const v1::RenderTileResponse& reply, const RenderSettings& settings,
                             const Rect& asked);

// The rectangle a worker answers for `asked`: clipped to the image, as the engines clip it.
Rect answered_rect(const RenderSettings& settings, const Rect& asked);

// True when the tiles hold the same bits: rect, size and every plane.
bool same_tile_bits(const v1::TileData& a, const v1::TileData& b);

// The part of `tile` inside `rect`, each plane cropped alike. `rect` must lie inside the tile's
// rect and the tile must be well formed (check_tile_reply passed).
v1::TileData crop_tile(const v1::TileData& tile, const Rect& rect);

}  // namespace farm
