#include "renderer/engine.h"

#include <fmt/format.h>

#include "renderer/geometry/scene_intersector.h"
#include "renderer/raster/raster_engine.h"
#include "renderer/scene/input_error.h"
#include "renderer/trace/whitted.h"

namespace farm {

bool engine_available(EngineKind engine) { return engine != EngineKind::Path; }

void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool) {
  switch (settings.engine) {
    case EngineKind::Raster:
      raster::prepare_frame(scene, settings, pool);
      return;
    case EngineKind::Whitted:
      cached_scene_intersector(scene, settings.accel);  // build the BVHs before the tiles start
      return;
    case EngineKind::Path:
      return;
  }
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
      whitted::render_tile(scene, settings, clipped, out);
      return;
    case EngineKind::Path:
      break;
  }
  throw InputError(fmt::format("render.engine: '{}' is not available in this build yet "
                               "(available: raster, whitted)",
                               to_string(settings.engine)));
}

}  // namespace farm
