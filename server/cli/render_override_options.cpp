#include "server/cli/render_override_options.h"

namespace farm {

void add_render_override_options(CLI::App& command, RenderOverrides& o) {
  // One heading in the help: these replace the job's own values, the others do not.
  constexpr const char* kGroup = "Render settings (replace the job file's)";
  command.add_option("--engine", o.engine, "Engine: raster, whitted or path (render.engine)")
      ->check(CLI::IsMember({"raster", "whitted", "path"}))
      ->group(kGroup);
  command.add_option("--width", o.width, "Image width in pixels (render.width)")
      ->check(CLI::Range(1, 16384))
      ->group(kGroup);
  command.add_option("--height", o.height, "Image height in pixels (render.height)")
      ->check(CLI::Range(1, 16384))
      ->group(kGroup);
  command.add_option("--spp", o.spp, "Samples per pixel (render.spp)")
      ->check(CLI::Range(1, 1 << 20))
      ->group(kGroup);
  command.add_option("--tile-size", o.tile_size, "Tile edge in pixels (render.tile_size)")
      ->check(CLI::Range(1, 16384))
      ->group(kGroup);
}

}  // namespace farm
