#include "renderer/raster/raster_engine.h"

namespace farm::raster {

void render_tile(const PreparedScene&, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out) {
  out.reset(tile, settings.aovs);  // replaced by the real rasterizer in this next commit
}

}  // namespace farm::raster
