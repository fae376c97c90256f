#include "server/render_command.h"

#include <fmt/format.h>

#include <chrono>
#include <stdexcept>

#include "renderer/engine.h"
#include "renderer/geometry/instance_intersector.h"
#include "renderer/image/box_overlay.h"
#include "renderer/image/exr_io.h"
#include "renderer/image/preview.h"
#include "renderer/prepared_scene.h"
#include "renderer/scene/input_error.h"
#include "renderer/scene/scene_builder.h"
#include "server/local_pipeline.h"
#include "server/progress_bar.h"
#include "server/validate_command.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string aov_list(const AovSet& aovs) {
  std::string s = "RGBA";
  for (Aov a : kAllAovs) {
    if (aovs.has(a)) s += fmt::format(" + {}", to_string(a));
  }
  return s;
}

// The film's colours with the boxes of the scene's BVH levels <= max_level drawn over them: the
// top level (over objects) in white, each object's own tree in a colour per level.
TileBuffer with_bvh_overlay(const TileBuffer& film, const PreparedScene& scene, AccelKind accel,
                            int max_level) {
  TileBuffer image(film.rect(), AovSet{});
  image.paste(film);
  // Embree's tree is not ours to draw, and `naive` has none: show our SAH BVH for those. The
  // render may already have built (and cached) this intersector.
  const AccelKind drawn = accel == AccelKind::BvhMedian ? accel : AccelKind::Bvh;
  const auto cached = cached_scene_intersector(scene, drawn);
  const auto* intersector = dynamic_cast<const InstanceIntersector*>(cached.get());
  if (!intersector) throw std::logic_error("--show-bvh: expected our own BVH intersector");
  BoxOverlay overlay(image, scene.scene().camera);
  intersector->visit_bvh_boxes(max_level, [&](const BvhBox& box) {
    overlay.draw_box(box.bounds, box.to_world,
                     box.object < 0 ? glm::vec3(1.0f) : BoxOverlay::level_color(box.level));
  });
  return image;
}

}  // namespace

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
  if (o.image) job.output.image = *o.image;
  if (o.preview) job.output.preview = *o.preview;
}

void run_render_command(const RenderCommandOptions& options) {
  const Clock::time_point t_start = Clock::now();
  Job job = load_job(options.job_file, options.load);
  apply_overrides(job, options.overrides);
  if (options.overrides.show_bvh && job.output.preview.empty()) {
    throw InputError("--show-bvh draws over the preview, but this render writes none "
                     "(give --preview FILE.png)");
  }
  if (!job.output.preview.empty() && !preview_format_supported(job.output.preview)) {
    throw InputError(fmt::format("{}: output.preview: cannot write images of type '{}'",
                                 options.job_file.string(), job.output.preview.extension().string()));
  }

  const PreparedScene prepared(build_scene(job));
  const double load_ms = ms_since(t_start);

  const Clock::time_point t_render = Clock::now();
  TileBuffer film;
  {
    ProgressBar bar(fmt::format("rendering {}", job.name),
                    options.progress && ProgressBar::stderr_is_terminal());
    film = render_frame(prepared, job.render,
                        [&](const TileProgress& p) { bar.update(p.tiles_done, p.tiles_total); });
  }
  const double render_ms = ms_since(t_render);

  const Clock::time_point t_write = Clock::now();
  const ExrPixelType pixel_type =
      options.overrides.full_float ? ExrPixelType::Float : ExrPixelType::Half;
  write_exr(film, job.output.image, pixel_type);
  if (!job.output.preview.empty()) {
    if (options.overrides.show_bvh) {
      write_preview(with_bvh_overlay(film, prepared, job.render.accel, *options.overrides.show_bvh),
                    job.output.preview);
    } else {
      write_preview(film, job.output.preview);
    }
  }
  const double write_ms = ms_since(t_write);

  const RenderSettings& r = job.render;
  const std::size_t tiles = split_into_tiles(r.width, r.height, r.tile_size).size();
  fmt::print("job '{}': {} engine, {}x{}, {} spp, {} triangles in {} object(s)\n", job.name,
             to_string(r.engine), r.width, r.height, r.spp, prepared.triangle_count(),
             prepared.objects().size());
  fmt::print("wrote {} ({}, {} EXR)\n", job.output.image.string(), aov_list(r.aovs),
             pixel_type == ExrPixelType::Half ? "half" : "float");
  if (!job.output.preview.empty()) {
    fmt::print("wrote {} (sRGB preview{})\n", job.output.preview.string(),
               options.overrides.show_bvh
                   ? fmt::format(", BVH levels <= {} drawn over it", *options.overrides.show_bvh)
                   : std::string());
  }
  if (film.stats().samples > 0) {
    fmt::print("samples: {} traced, {} NaN/inf samples caught and dropped\n", film.stats().samples,
               film.stats().invalid_samples);
  }
  if (film.stats().rays > 0) {
    fmt::print("rays: {} traced ({:.2f} Mrays/s)\n", film.stats().rays,
               static_cast<double>(film.stats().rays) / (render_ms * 1e3));
  }
  fmt::print("time: load+prepare {:.1f} ms, render {:.1f} ms ({} tiles of {} px, {} threads), "
             "write {:.1f} ms, total {:.1f} ms\n",
             load_ms, render_ms, tiles, r.tile_size, resolve_thread_count(r.threads), write_ms,
             ms_since(t_start));
  if (job.embree_rays > 0) {
    const AccelKind accel = accel_to_validate(r.accel);
    const AccelValidation v = validate_against_embree(prepared, r, accel,
                                                      static_cast<std::uint64_t>(job.embree_rays));
    fmt::print("{} ({} vs embree{})\n", v.summary(), to_string(accel),
               validation_passes(v) ? "" : "; more hit/miss disagreements than 0.001% of rays");
  }
}

}  // namespace farm
