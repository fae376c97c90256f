#include "server/cli/render_override_options.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <string>
#include <vector>

#include "renderer/job/frame_range.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/render_settings.h"

namespace farm {

void add_render_override_options(CLI::App& command, RenderOverrides& o) {
  // One heading in the help: these replace the job's own values, the others do not.
  constexpr const char* kGroup = "Render settings (replace the job file's)";
  const std::vector<std::string> engines(kEngineNames.begin(), kEngineNames.end());
  command.add_option("--engine", o.engine,
                     fmt::format("Engine: {} (render.engine)", fmt::join(engines, ", ")))
      ->check(CLI::IsMember(engines))
      ->group(kGroup);
  command.add_option("--width", o.width, "Image width in pixels (render.width)")
      ->check(CLI::Range(1, kMaxImageSide))
      ->group(kGroup);
  command.add_option("--height", o.height, "Image height in pixels (render.height)")
      ->check(CLI::Range(1, kMaxImageSide))
      ->group(kGroup);
  command.add_option("--spp", o.spp, "Samples per pixel (render.spp)")
      ->check(CLI::Range(1, kMaxSpp))
      ->group(kGroup);
  command.add_option("--tile-size", o.tile_size, "Tile edge in pixels (render.tile_size)")
      ->check(CLI::Range(1, kMaxTileSize))
      ->group(kGroup);
  command
      .add_option_function<std::string>(
          "--frames",
          [&o](const std::string& text) {
            const auto pick = parse_frame_pick(text);
            if (!pick) throw CLI::ValidationError("--frames", "expected FIRST-LAST or FRAME, such as 10-20 or 5");
            o.frames = *pick;
          },
          "Frames of the job's range to render, FIRST-LAST or one FRAME (frames.only)")
      ->type_name("RANGE")
      ->group(kGroup);
}

}  // namespace farm
