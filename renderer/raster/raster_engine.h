#pragma once
// The software rasterizer: vertex stage, homogeneous clipping, edge-function coverage with a
// top-left fill rule on a fixed-point grid, perspective-correct interpolation, z-buffer, and
// Blinn-Phong shading (renderer/scene/blinn_phong.h).
#include "renderer/image/tile_buffer.h"
#include "renderer/prepared_scene.h"
#include "renderer/render_settings.h"

namespace farm::raster {

void render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out);

}  // namespace farm::raster
