#include "server/client/render_overrides.h"

#include <fmt/format.h>

#include "renderer/scene/input_error.h"

namespace farm {

void apply_overrides(Job& job, const RenderOverrides& o) {
  RenderSettings& r = job.render;
  if (o.engine) {
    const auto engine = engine_from_string(*o.engine);
    if (!engine) throw InputError(fmt::format("--engine: unknown engine '{}'", *o.engine));
    r.engine = *engine;
  }
  if (o.width) r.width = *o.width;
  if (o.height) r.height = *o.height;
  if (o.spp) r.spp = *o.spp;
  if (o.threads) r.threads = *o.threads;
  if (o.tile_size) r.tile_size = *o.tile_size;
  if (o.max_depth) r.max_depth = *o.max_depth;
  if (o.seed) r.seed = *o.seed;
  for (const std::string& name : o.add_aovs) {
    const auto aov = aov_from_string(name);
    if (!aov) throw InputError(fmt::format("unknown AOV '{}'", name));
    r.aovs.add(*aov);
  }
  if (o.image) job.output.image = *o.image;
  if (o.preview) job.output.preview = *o.preview;
}

}  // namespace farm
