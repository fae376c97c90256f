#pragma once
// The frame both ray engines' render_tile share (docs/architecture.md, "The engine contract"): the
// buffer reset to the tile, the scene's intersector fetched (built once per frame and shared by
// every tile), a tracer made over it, and every pixel traced in row order. A stop drops the tile
// whole, so a buffer is complete or empty, never half-written; the rays traced are counted in the
// buffer's stats either way. What a pixel is, is each engine's own (whitted.cpp, path_tracer.cpp).
#include <cstdint>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/cancel_flag.h"

namespace farm {

// `make_tracer(intersector, poll)` returns the engine's tracer (by value: no copy is made), which
// counts its work on `poll` (looked at every `poll_every` units) and says rays_traced();
// `trace_pixel(tracer, x, y)` writes pixel (x, y) of `out` and returns false when the poll said
// stop.
template <typename MakeTracer, typename TracePixel>
StopReason trace_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile, TileBuffer& out,
                      const CancelFlag& cancel, int poll_every, MakeTracer&& make_tracer,
                      TracePixel&& trace_pixel) {
  out.reset(tile, settings.aovs);
  if (tile.empty()) return StopReason::None;
  const auto intersector = cached_scene_intersector(scene, settings.accel, cancel);
  CancelPoll poll(cancel, poll_every);
  const auto tracer = make_tracer(*intersector, poll);
  for (int y = tile.y0; y < tile.y1; ++y) {
    for (int x = tile.x0; x < tile.x1; ++x) {
      if (!trace_pixel(tracer, x, y)) {
        out.stats().rays += tracer.rays_traced();
        out.discard_pixels();
        return cancel.reason();
      }
    }
  }
  out.stats().rays += tracer.rays_traced();
  return StopReason::None;
}

// Pixel (x, y)'s index in the frame: the key of its random numbers (sampler.h).
inline std::uint64_t pixel_index(const RenderSettings& settings, int x, int y) {
  return static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(settings.width) + static_cast<std::uint64_t>(x);
}

}  // namespace farm
