// `farm`: the render farm's command line. Exit codes: 0 ok, 2 bad input, 1 internal error.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <exception>

#include "renderer/scene/input_error.h"
#include "server/bench/farm_bench.h"
#include "server/bench/path_bench.h"
#include "server/bench/raster_bench.h"
#include "server/bench/render_bench.h"
#include "server/bench/rt_bench.h"
#include "server/cli/client_commands.h"
#include "server/cli/info_command.h"
#include "server/cli/render_command.h"
#include "server/cli/scheduler_command.h"
#include "server/cli/validate_command.h"
#include "server/cli/worker_command.h"
#include "server/common/service_error.h"

namespace {

constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 1;

void add_render_command(CLI::App& app, farm::RenderCommandOptions& o, std::string& preview) {
  CLI::App* render = app.add_subcommand(
      "render", "Render a job in this process (embedded scheduler and local worker threads)");
  render->add_option("job", o.job_file, "Job file (JSON, see jobs/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  render->add_option("--engine", o.overrides.engine, "Engine: raster, whitted or path")
      ->check(CLI::IsMember({"raster", "whitted", "path"}));
  render->add_option("--width", o.overrides.width, "Image width in pixels")
      ->check(CLI::Range(1, 16384));
  render->add_option("--height", o.overrides.height, "Image height in pixels")
      ->check(CLI::Range(1, 16384));
  render->add_option("--spp", o.overrides.spp, "Samples per pixel")->check(CLI::Range(1, 1 << 20));
  render->add_option("--threads", o.overrides.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024));
  render->add_option("--tile-size", o.overrides.tile_size, "Tile edge in pixels")
      ->check(CLI::Range(1, 16384));
  render->add_option("--out", o.overrides.image, "EXR output path (replaces output.image)");
  render->add_option("--preview", preview,
                     "Preview path, .png or .jpg (replaces output.preview; 'none' for no preview)");
  render->add_flag("--float", o.overrides.full_float, "Write 32-bit float EXR instead of half");
  render->add_option("--show-bvh", o.overrides.show_bvh,
                     "Draw the BVH boxes of levels <= DEPTH over the preview (white: the tree over "
                     "objects; colours: each object's tree by level)")
      ->check(CLI::Range(0, 64));
  render->add_option("--asset-root", o.load.asset_root,
                     "Folder that model files must lie in (default: the job file's folder)")
      ->check(CLI::ExistingDirectory);
  render->add_flag("--quiet", [&o](std::int64_t) { o.progress = false; }, "No progress bar");
}

CLI::App* add_worker_command(CLI::App& app, farm::WorkerOptions& o) {
  CLI::App* worker = app.add_subcommand(
      "worker", "Serve farm.v1.Worker (RenderTile) plus gRPC health and reflection");
  worker->add_option("--listen", o.listen,
                     "Address to serve on, HOST:PORT (port 0 picks a free port; the address is "
                     "printed as 'worker listening on HOST:PORT')")
      ->required();
  worker->add_option("--threads", o.threads, "Render threads shared by all calls (0 = all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  worker->add_option("--scheduler", o.scheduler,
                     "Scheduler HOST:PORT to fetch assets this worker lacks from (by SHA-256); "
                     "without it, a job whose assets are not in the cache fails with "
                     "FAILED_PRECONDITION");
  worker->add_option("--cache-dir", o.cache_dir,
                     "Folder for fetched assets (blobs/<sha256>) and laid-out scenes "
                     "(scenes/<scene hash>/) (default: <temp>/farm-worker-cache)");
  worker->add_option("--max-scenes", o.max_scenes, "Prepared scenes kept in memory (LRU)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  worker->add_option("--cache-memory", o.cache_memory_mb,
                     "Approximate memory budget of the prepared scenes, MiB (LRU)")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  worker->footer("Each RenderTile call renders its rectangle on all render threads, in 16x16 "
                 "sub-tiles shared with concurrent calls; a call stops when its client cancels "
                 "or its deadline passes. Scenes are prepared once per scene hash. SIGINT or "
                 "SIGTERM shut the worker down cleanly.");
  return worker;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"farm: render farm batch service.\n"
               "  farm render JOB   render a job locally to EXR + PNG preview\n"
               "  farm info FILE    show what a model or job file contains\n"
               "  farm validate JOB compare our BVH's ray hits with Embree's on a job's scene\n"
               "  farm bench raster measure rasterizer speed and thread scaling\n"
               "  farm bench rt     compare our BVHs with Embree\n"
               "  farm bench path   path tracer throughput (and Mitsuba's, side by side)\n"
               "  farm bench farm   the farm's overhead over loopback, jobs per second\n"
               "  farm scheduler    serve jobs over gRPC: tiles to workers, merged EXR out\n"
               "  farm worker       serve tiles to a scheduler over gRPC\n"
               "  farm submit JOB   send a job to a scheduler (status, watch, cancel, fetch follow it)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "farm 0.1.0");

  farm::RenderCommandOptions render_options;
  std::string preview;
  add_render_command(app, render_options, preview);

  std::filesystem::path info_file;
  farm::JobLoadOptions info_load;
  CLI::App* info = app.add_subcommand("info", "Print a model's or a job's statistics");
  info->add_option("file", info_file, "Model (.dae .obj .ply .gltf .glb) or job (.json)")
      ->required()
      ->check(CLI::ExistingFile);
  info->add_option("--asset-root", info_load.asset_root, "Asset root for a job's model files")
      ->check(CLI::ExistingDirectory);

  farm::ValidateCommandOptions validate_options;
  CLI::App* validate = app.add_subcommand(
      "validate", "Compare our acceleration structure's ray hits with Embree's on a job's scene");
  validate->add_option("job", validate_options.job_file, "Job file (JSON, see jobs/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  validate->add_option("--rays", validate_options.rays,
                       "Rays to compare, half primary and half from inside the scene "
                       "(default: the job's validate.embree_rays, else 100000)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 32));
  validate->add_option("--accel", validate_options.accel,
                       "Ours to compare: bvh, bvh-median or naive (default: the job's render.accel; "
                       "bvh when that is embree)")
      ->check(CLI::IsMember({"bvh", "bvh-median", "naive"}));
  validate->add_option("--asset-root", validate_options.load.asset_root,
                       "Folder that model files must lie in (default: the job file's folder)")
      ->check(CLI::ExistingDirectory);
  validate->footer("Exit codes: 0 the hits agree (hit/miss disagreements at most 0.001% of the "
                   "rays), 1 they do not (or an internal error), 2 bad input.");

  farm::RasterBenchOptions raster_bench;
  CLI::App* bench = app.add_subcommand("bench", "Measure engine performance");
  bench->require_subcommand(1);
  CLI::App* bench_raster = bench->add_subcommand(
      "raster", "Rasterizer frame times for the cow and the 100-cow grid at 1920x1080 "
                "across thread counts");
  bench_raster->add_option("--model", raster_bench.model,
                           "The cow model (default ../shared/assets/dae/cow.dae)");
  bench_raster->add_option("--threads", raster_bench.threads, "Thread counts to measure")
      ->delimiter(',')
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  bench_raster->add_option("--frames", raster_bench.frames, "Timed frames per configuration")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  bench_raster->add_option("--warmup", raster_bench.warmup, "Untimed frames first")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  bench_raster->add_option("--scene", raster_bench.scene, "Which scene: cow, cow-grid-100 or all")
      ->check(CLI::IsMember({"cow", "cow-grid-100", "all"}))
      ->capture_default_str();
  bench_raster->add_flag("--oversubscribe", raster_bench.oversubscribe,
                         "Also run thread counts above the number of cores");
  bench_raster->add_option("--width", raster_bench.width, "Image width")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  bench_raster->add_option("--height", raster_bench.height, "Image height")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();

  farm::RtBenchOptions rt_bench;
  CLI::App* bench_rt = bench->add_subcommand(
      "rt", "Our BVHs against Embree: build time and single-thread Mrays/s (primary and incoherent, "
            "closest and any hit) on cow, bunny, CBbunny and the 100-cow grid");
  bench_rt->add_option("--assets", rt_bench.assets,
                       "The lab's assets folder (default ../shared/assets)");
  bench_rt->add_option("--rays", rt_bench.rays, "Rays per set")
      ->check(CLI::Range(1000, 100'000'000))
      ->capture_default_str();

  farm::PathBenchOptions path_bench;
  CLI::App* bench_path = bench->add_subcommand(
      "path", "Path tracer Msamples/s and Mrays/s on the Cornell box and CBbunny at 512x512, on one "
              "thread and all; with --mitsuba, Mitsuba 3 scalar_rgb on the same Cornell box beside it");
  bench_path->add_option("--job", path_bench.cornell_job, "The Cornell box job")->capture_default_str();
  bench_path->add_option("--assets", path_bench.assets,
                         "The lab's assets folder, for CBbunny (default ../shared/assets)");
  bench_path->add_option("--threads", path_bench.threads, "Thread counts (default: 1 and all)")
      ->delimiter(',')
      ->check(CLI::Range(1, 1024));
  bench_path->add_option("--spp", path_bench.spp, "Samples per pixel")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  bench_path->add_option("--width", path_bench.width, "Image width")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  bench_path->add_option("--height", path_bench.height, "Image height")
      ->check(CLI::Range(1, 16384))
      ->capture_default_str();
  bench_path->add_option("--scene", path_bench.scene, "Which scene: cornell, cbbunny or all")
      ->check(CLI::IsMember({"cornell", "cbbunny", "all"}))
      ->capture_default_str();
  bench_path->add_option("--mitsuba", path_bench.mitsuba_python,
                         "A Python with the mitsuba package (see tools/requirements-mitsuba.txt): "
                         "time Mitsuba 3 scalar_rgb on the Cornell box too");
  bench_path->add_option("--mitsuba-script", path_bench.mitsuba_script,
                         "The script that renders a job with Mitsuba")
      ->capture_default_str();
  farm::WorkerOptions worker_options;
  CLI::App* worker = add_worker_command(app, worker_options);
  farm::FarmBenchOptions farm_bench;
  CLI::App* bench_farm = bench->add_subcommand(
      "farm", "The farm's overhead: the Cornell box path traced through farm render, a scheduler with 1 "
              "and with 2 workers over loopback; then tiny jobs for jobs/s and submit latency");
  bench_farm->add_option("--job", farm_bench.job, "The job to render")->capture_default_str();
  bench_farm->add_option("--spp", farm_bench.spp, "Samples per pixel")->check(CLI::Range(1, 65536))->capture_default_str();
  bench_farm->add_option("--width", farm_bench.width, "Image width")->check(CLI::Range(1, 16384))->capture_default_str();
  bench_farm->add_option("--height", farm_bench.height, "Image height")->check(CLI::Range(1, 16384))->capture_default_str();
  bench_farm->add_option("--repeats", farm_bench.repeats, "Renders per configuration (median reported)")
      ->check(CLI::Range(1, 100))->capture_default_str();
  bench_farm->add_option("--tiles-per-worker", farm_bench.tiles_per_worker,
                         "The scheduler's --tiles-per-worker for (b), (c) and the tiny jobs")
      ->check(CLI::Range(1, 64))->capture_default_str();
  bench_farm->add_option("--batch-ms", farm_bench.batch_ms,
                         "The scheduler's --batch-ms for (a), (b), (c) and the tiny jobs (0: one tile a call)")
      ->check(CLI::Range(0, 600000))->capture_default_str();
  bench_farm->add_option("--two-worker-threads", farm_bench.two_worker_threads,
                         "--threads of each worker in (c) (0: all cores each, as `farm worker` defaults)")
      ->check(CLI::Range(0, 1024))->capture_default_str();
  bench_farm->add_option("--tiny-jobs", farm_bench.tiny_jobs, "Tiny jobs to submit")->check(CLI::Range(1, 100000))->capture_default_str();

  farm::RenderBenchOptions render_bench;
  CLI::App* bench_render = bench->add_subcommand(
      "render", "The whole `farm render` command (process start to exit) against the bare engine frame "
                "on the same scene: the lab's cow job and a 100-cow grid at 1920x1080, 1 and 2 threads");
  bench_render->add_option("--cow-job", render_bench.cow_job, "The cow job")->capture_default_str();
  bench_render->add_option("--asset-root", render_bench.asset_root, "Asset root of the cow job")
      ->capture_default_str();
  bench_render->add_option("--threads", render_bench.threads, "Thread counts")
      ->delimiter(',')->check(CLI::Range(1, 1024));
  bench_render->add_option("--repeats", render_bench.repeats, "Rounds (medians reported)")
      ->check(CLI::Range(1, 100))->capture_default_str();
  bench_render->add_option("--scene", render_bench.scene, "Which scene: cow, cow-grid-100 or all")
      ->check(CLI::IsMember({"cow", "cow-grid-100", "all"}))->capture_default_str();

  farm::SchedulerCommandOptions scheduler_options;
  CLI::App* scheduler = farm::add_scheduler_command(app, scheduler_options);
  farm::ClientCommands client_commands;
  farm::add_client_commands(app, client_commands);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }

  try {
    if (app.got_subcommand("render")) {
      if (!preview.empty()) render_options.overrides.preview = preview == "none" ? "" : preview;
      farm::run_render_command(render_options);
    } else if (bench_rt->parsed()) {
      farm::run_rt_bench(rt_bench);
    } else if (bench_render->parsed()) {
      farm::run_render_bench(render_bench);
    } else if (bench_farm->parsed()) {
      farm::run_farm_bench(farm_bench);
    } else if (bench_path->parsed()) {
      farm::run_path_bench(path_bench);
    } else if (bench_raster->parsed()) {
      farm::run_raster_bench(raster_bench);
    } else if (app.got_subcommand("info")) {
      farm::run_info_command(info_file, info_load);
    } else if (validate->parsed()) {
      return farm::run_validate_command(validate_options);
    } else if (worker->parsed()) {
      return farm::run_worker_command(worker_options);
    } else if (scheduler->parsed()) {
      return farm::run_scheduler_command(scheduler_options);
    } else if (const int code = farm::run_client_command(client_commands); code >= 0) {
      return code;
    }
  } catch (const farm::InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kExitBadInput;
  } catch (const farm::ServiceError& e) {
    fmt::print(stderr, "error: {}\n", e.what());  // e.g. the scheduler is not reachable
    return kExitInternal;
  } catch (const std::exception& e) {
    fmt::print(stderr, "internal error: {}\n", e.what());
    return kExitInternal;
  }
  return 0;
}
