#include "renderer/engine.h"

#include <fmt/format.h>

#include "renderer/accel/scene_intersector.h"
#include "renderer/raster/raster_engine.h"
#include "renderer/trace/path_tracer.h"
#include "renderer/trace/whitted.h"
#include "renderer/util/input_error.h"

namespace farm {

void prepare_frame(const PreparedScene& scene, const RenderSettings& settings, ThreadPool& pool,
                   const CancelFlag& cancel) {
  switch (settings.engine) {
    case EngineKind::Raster:
      raster::prepare_frame(scene, settings, pool, cancel);
      return;
    case EngineKind::Whitted:
    case EngineKind::Path:
      cached_scene_intersector(scene, settings.accel, cancel);  // the BVHs before the tiles start
      return;
  }
}

void render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                 TileBuffer& out) {
  // A flag that never stops the render: the tile always comes back complete.
  static_cast<void>(render_tile(scene, settings, tile, out, CancelFlag::never()));
}

StopReason render_tile(const PreparedScene& scene, const RenderSettings& settings, const Rect& tile,
                       TileBuffer& out, const CancelFlag& cancel) {
  const Rect image{0, 0, settings.width, settings.height};
  const Rect clipped = tile.intersect(image);
  // A pass the frame does not have (pass 1 of a raster frame, pass 4 of 4) is refused before any
  // work: rendering nothing, or all samples again, would merge into a wrong image.
  static_cast<void>(samples_to_render(settings));
  try {
    switch (settings.engine) {
      case EngineKind::Raster:
        return raster::render_tile(scene, settings, clipped, out, cancel);
      case EngineKind::Whitted:
        return whitted::render_tile(scene, settings, clipped, out, cancel);
      case EngineKind::Path:
        return path::render_tile(scene, settings, clipped, out, cancel);
    }
  } catch (const RenderStopped& stopped) {  // in the frame's set-up, which the tile waited for
    out.discard_pixels();
    return stopped.reason();
  }
  throw InputError(fmt::format("render.engine: unknown engine {}", static_cast<int>(settings.engine)));
}

}  // namespace farm
