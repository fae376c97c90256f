#pragma once
// The `path` engine: unidirectional Monte Carlo path tracing with next-event estimation at every
// non-specular vertex (area lights sampled by power, point lights), combined with BSDF sampling
// by multiple importance sampling (power heuristic), and Russian roulette after a few bounces.
// Samples are box-filtered over the pixel; every random number comes from the counter-based
// sampler, so any tiling gives the same image. With sample passes (RenderSettings::pass) a call
// traces only its pass's samples, by their global index in the pixel, and writes their mean,
// coverage and variance: what PassAccumulator merges with the other passes.
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/cancel_flag.h"

namespace farm::path {

// Polls `cancel` every few camera samples; see farm::render_tile for what a stopped render leaves.
StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel);

}  // namespace farm::path
