#include "server/cli/render_command.h"

#include <fmt/format.h>

#include <chrono>
#include <future>
#include <memory>
#include <stdexcept>

#include "renderer/accel/instance_intersector.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/engine.h"
#include "renderer/image/box_overlay.h"
#include "renderer/image/exr_io.h"
#include "renderer/image/preview.h"
#include "renderer/job/job_limits.h"
#include "renderer/job/scene_builder.h"
#include "renderer/job/video_format.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "server/cli/job_display.h"
#include "server/cli/job_file_options.h"
#include "server/cli/log_level_option.h"
#include "server/cli/progress_bar.h"
#include "server/cli/render_override_options.h"
#include "server/cli/validate_command.h"
#include "server/client/job_submission.h"
#include "server/common/server_shutdown.h"
#include "server/common/video_encoder.h"
#include "server/embedded/embedded_farm.h"
#include "server/scheduler/jobs/unit_grid.h"

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

void run_render_command(const RenderCommandOptions& options) {
  const Clock::time_point t_start = Clock::now();
  const JobSubmission submission = make_job_submission(options.job_file, options.load, options.overrides);
  const Job& job = submission.job;
  if (options.overrides.show_bvh && job.output.preview.empty()) {
    throw InputError("--show-bvh draws over the preview, but this render writes none "
                     "(give --preview FILE.png)");
  }
  if (!job.output.preview.empty() && !preview_format_supported(job.output.preview)) {
    throw InputError(fmt::format("{}: output.preview: cannot write images of type '{}'",
                                 options.job_file.string(), job.output.preview.extension().string()));
  }
  if (!job.output.video.empty()) {
    // Said before a frame renders, not after the last one.
    if (const FfmpegLookup ffmpeg = find_ffmpeg(); !ffmpeg) {
      throw InputError(fmt::format("{}: output.video: making the video {} needs ffmpeg, and {} (or render "
                                   "without the video: --video none)",
                                   options.job_file.string(), job.output.video.string(), ffmpeg.problem));
    }
    if (options.overrides.show_bvh) {
      throw InputError("--show-bvh draws over the first frame's preview only, and the video is made from every "
                       "frame's: give --video none with it");
    }
  }

  // The same scheduler and worker code a farm runs, in this process: the job is submitted,
  // split into tiles, rendered by an in-process worker on all threads and merged into the
  // job's output files.
  EmbeddedFarmOptions farm_options;
  farm_options.threads = job.render.threads;
  farm_options.exr_type = options.overrides.full_float ? ExrPixelType::Float : ExrPixelType::Half;
  // The models load on a thread of their own while the farm is set up (its job store, its
  // threads), two steps one thread took in turn: the 100-cow grid's frame set-up starts at
  // 18.7-19.2 ms from the process's start instead of 19.9-21.7.
  std::future<LoadedScene> loading = std::async(std::launch::async, [&job] { return load_job_scene(job); });
  auto farm = std::make_unique<EmbeddedFarm>(farm_options);
  const double load_ms = ms_since(t_start);

  const Clock::time_point t_render = Clock::now();
  EmbeddedResult result;
  {
    ProgressBar bar(fmt::format("rendering {}", job.name),
                    options.progress && ProgressBar::stderr_is_terminal());
    LocalRunOptions run;
    // --show-bvh: the preview is drawn here, over the merged frame, instead of by the merge.
    run.write_preview = !options.overrides.show_bvh;
    run.keep_frame = options.overrides.show_bvh.has_value();
    run.loaded = loading.get();  // a model that failed to load throws its InputError here
    result = farm->run_local(
        submission, [&](const v1::Job& j) { bar.update(j.tiles_done(), j.tiles_total(), frames_of(j)); }, run);
  }
  const double render_ms = ms_since(t_render);
  if (result.job.state() != v1::JOB_STATE_SUCCEEDED) {
    throw std::runtime_error(fmt::format("{}: the render failed: {}", options.job_file.string(),
                                         result.job.failure_reason()));
  }

  const Clock::time_point t_overlay = Clock::now();
  if (options.overrides.show_bvh && !job.output.preview.empty()) {
    write_preview(with_bvh_overlay(*result.frame, *result.scene, job.render.accel, *options.overrides.show_bvh),
                  job.output.preview);
  }
  const double overlay_ms = ms_since(t_overlay);

  const RenderSettings& r = job.render;
  const v1::TileStats& stats = result.job.stats();
  fmt::print("job '{}': {} engine, {}x{}, {} spp, {} object(s)\n", job.name, to_string(r.engine), r.width,
             r.height, r.spp, job.scene.objects.size());
  // A job with frames: how many, and the first and last frame's files.
  const std::vector<int> frames = job_frames(job);
  const Job last = job_at_frame(job, frames.back());
  const auto written = [&](const std::filesystem::path& first, const std::filesystem::path& final_frame) {
    if (frames.size() == 1) return first.string();
    return fmt::format("{} frames, {} .. {}", frames.size(), first.string(), final_frame.string());
  };
  fmt::print("wrote {} ({}, {} EXR)\n", written(job.output.image, last.output.image), aov_list(r.aovs),
             farm_options.exr_type == ExrPixelType::Half ? "half" : "float");
  if (!job.output.preview.empty()) {
    fmt::print("wrote {} (sRGB preview{})\n", written(job.output.preview, last.output.preview),
               options.overrides.show_bvh
                   ? fmt::format(", BVH levels <= {} drawn over it", *options.overrides.show_bvh)
                   : std::string());
  }
  if (!result.video.empty()) {
    fmt::print("wrote {} ({}, {} frames at {} fps)\n", result.video.string(),
               video_codec_name(*video_format_of(result.video)), frames.size(), job.frames->fps);
  }
  if (stats.samples() > 0) {
    fmt::print("samples: {} traced, {} NaN/inf samples caught and dropped\n", stats.samples(),
               stats.invalid_samples());
  }
  if (stats.rays() > 0) {
    fmt::print("rays: {} traced ({:.2f} Mrays/s)\n", stats.rays(),
               static_cast<double>(stats.rays()) / (render_ms * 1e3));
  }
  const std::string passes =
      result.job.passes() > 1 ? fmt::format(" in {} sample passes", result.job.passes()) : std::string();
  // The units the embedded farm cut the frames into: k x k of the job's tiles (unit_grid.h).
  const int unit_edge = UnitGrid(r, farm_options.min_unit_edge).edge();
  fmt::print("time: job+farm set-up {:.1f} ms (models loading meanwhile), rest of load+render+merge+write "
             "{:.1f} ms ({} units of {} px in tiles of {} px{}, {} threads), {}total {:.1f} ms\n",
             load_ms, render_ms, result.job.tiles_total(), unit_edge, r.tile_size, passes,
             resolve_thread_count(r.threads),
             options.overrides.show_bvh ? fmt::format("BVH overlay {:.1f} ms, ", overlay_ms) : std::string(),
             ms_since(t_start));
  if (!result.job.validation().empty()) fmt::print("{}\n", result.job.validation());
  // Done and written: the process ends here rather than taking the embedded farm apart (its
  // threads woken and joined one by one, its scene and frame freed block by block): the 100-cow
  // grid's last 3.0-3.9 ms, from its files written to its exit, are 1.1-2.2 ms this way. Only its
  // scratch folder would outlive the process.
  farm->remove_scratch_folder();
  exit_abandoning_calls(0);
}

void add_render_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<RenderCommandOptions>();
  CLI::App* render = app.add_subcommand(
      "render", "Render a job in this process (embedded scheduler and local worker threads)");
  add_job_file_options(*render, o->job_file, o->load);
  add_render_override_options(*render, o->overrides);
  render->add_option("--threads", o->overrides.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, kMaxThreads));
  render->add_option("--out", o->overrides.image, "EXR output path (replaces output.image)");
  render->add_option_function<std::string>(
      "--preview",
      [o](const std::string& preview) {
        if (!preview.empty()) o->overrides.preview = preview == "none" ? "" : preview;
      },
      "Preview path, .png or .jpg (replaces output.preview; 'none' for no preview)");
  render->add_option_function<std::string>(
      "--video",
      [o](const std::string& video) {
        if (!video.empty()) o->overrides.video = video == "none" ? "" : video;
      },
      "Video path, .mp4 .mkv or .webm, made by ffmpeg from the previews (replaces output.video; 'none' for "
      "no video)");
  render->add_flag("--float", o->overrides.full_float, "Write 32-bit float EXR instead of half");
  render->add_option("--show-bvh", o->overrides.show_bvh,
                     "Draw the BVH boxes of levels <= DEPTH over the preview (white: the tree over "
                     "objects; colours: each object's tree by level)")
      ->check(CLI::Range(0, 64));
  render->add_flag("--quiet", [o](std::int64_t) { o->progress = false; }, "No progress bar");
  add_log_level_option(*render, "warn");
  commands.add(render, [o]() -> int { run_render_command(*o); });
}

}  // namespace farm
