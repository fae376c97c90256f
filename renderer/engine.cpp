#include "renderer/engine.h"

#include <fmt/format.h>

#include "renderer/raster/raster_engine.h"
#include "renderer/scene/input_error.h"

namespace farm {

bool engine_available(EngineKind engine) { return engine == EngineKind::Raster; }

void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool) {
  if (settings.engine == EngineKind::Raster) raster::prepare_frame(scene, settings, pool);
}

void render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out) {
  const Rect image{0, 0, settings.width, settings.height};
  const Rect clipped = tile.intersect(image);
  switch (settings.engine) {
    case EngineKind::Raster:
      raster::render_tile(scene, settings, clipped, out);
      return;
    case EngineKind::Whitted:
    case EngineKind::Path:
      break;
  }
  throw InputError(fmt::format("render.engine: '{}' is not available in this build yet "
                               "(available: raster)",
                               to_string(settings.engine)));
}

}  // namespace farm
