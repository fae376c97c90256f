#pragma once
// Whitted-style ray tracing: a primary ray per sample, Blinn-Phong at the hit with a shadow ray
// per light, and recursion for mirrors (shininess >= 1000, weighted by the Fresnel reflectance)
// and smooth dielectrics (Material::transmitted_share of the surface, when transmission > 0 and
// ior > 1: Fresnel-weighted reflection and refraction, total internal reflection included; the
// rest shaded as if opaque), up to max_depth bounces.
#include "renderer/accel/prepared_scene.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "renderer/util/cancel_flag.h"

namespace farm::whitted {

// Polls `cancel` every few camera samples; see farm::render_tile for what a stopped render leaves.
StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel);

}  // namespace farm::whitted
