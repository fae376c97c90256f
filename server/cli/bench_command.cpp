#include "server/cli/bench_command.h"

#include <memory>
#include <string>
#include <vector>

#include "renderer/job/job_limits.h"
#include "server/bench/farm_bench.h"
#include "server/bench/flip_bench.h"
#include "server/bench/dispatch_bench.h"
#include "server/bench/frames_bench.h"
#include "server/bench/grade_bench.h"
#include "server/bench/path_bench.h"
#include "server/bench/raster_bench.h"
#include "server/bench/regress_bench.h"
#include "server/bench/render_bench.h"
#include "server/bench/rt_bench.h"
#include "server/scheduler/store/postgres_connection.h"

namespace farm {
namespace {

// Binds the options of a sub-command to `*options`, which its runner then hands to `run`.
template <typename Options>
void add_runner(CommandTable& commands, CLI::App* command, std::shared_ptr<Options> options,
                void (*run)(const Options&)) {
  commands.add(command, [options, run] {
    run(*options);
    return 0;
  });
}

// The rendered image's size; the benchmarks' defaults differ, the job's limits do not.
void add_image_size_options(CLI::App& command, int& width, int& height) {
  command.add_option("--width", width, "Image width")
      ->check(CLI::Range(1, kMaxImageSide))
      ->capture_default_str();
  command.add_option("--height", height, "Image height")
      ->check(CLI::Range(1, kMaxImageSide))
      ->capture_default_str();
}

// The path-traced benchmarks' samples per pixel (bounded below the job's limit: a benchmark
// should end).
void add_spp_option(CLI::App& command, int& spp) {
  command.add_option("--spp", spp, "Samples per pixel")->check(CLI::Range(1, 65536))->capture_default_str();
}

// A list of thread counts to measure, "1,2,4".
CLI::Option* add_thread_counts_option(CLI::App& command, std::vector<int>& threads, const std::string& what) {
  return command.add_option("--threads", threads, what)->delimiter(',')->check(CLI::Range(1, kMaxThreads));
}

// The benchmarks over the lab's cow: the cow alone, the 10 x 10 grid of it, or both.
void add_cow_scene_option(CLI::App& command, std::string& scene) {
  command.add_option("--scene", scene, "Which scene: cow, cow-grid-100 or all")
      ->check(CLI::IsMember({"cow", "cow-grid-100", "all"}))
      ->capture_default_str();
}

void add_raster_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<RasterBenchOptions>();
  CLI::App* raster = bench.add_subcommand(
      "raster", "Rasterizer frame times for the cow and the 100-cow grid at 1920x1080 "
                "across thread counts");
  raster->add_option("--model", o->model, "The cow model (default ../shared/assets/dae/cow.dae)");
  add_thread_counts_option(*raster, o->threads, "Thread counts to measure")->capture_default_str();
  raster->add_option("--frames", o->frames, "Timed frames per configuration")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  raster->add_option("--warmup", o->warmup, "Untimed frames first")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  add_cow_scene_option(*raster, o->scene);
  raster->add_flag("--oversubscribe", o->oversubscribe,
                   "Also run thread counts above the number of cores");
  add_image_size_options(*raster, o->width, o->height);
  add_runner(commands, raster, o, run_raster_bench);
}

void add_rt_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<RtBenchOptions>();
  CLI::App* rt = bench.add_subcommand(
      "rt", "Our BVHs against Embree (through the farm's adapter, and called directly): build time and Mrays/s "
            "(primary and incoherent, closest and any hit) on cow, bunny, CBbunny and the 100-cow grid");
  rt->add_option("--assets", o->assets, "The lab's assets folder (default ../shared/assets)");
  rt->add_option("--model", o->models,
                 "A model file to time instead of the lab's four scenes (any format farm reads; repeat for more)")
      ->check(CLI::ExistingFile);
  rt->add_option("--rays", o->rays, "Rays per set")
      ->check(CLI::Range(1000, 100'000'000))
      ->capture_default_str();
  add_thread_counts_option(*rt, o->threads, "Thread counts, comma-separated: a table each (e.g. 1,2,4,8,16)")
      ->capture_default_str();
  rt->add_option("--repeats", o->repeats,
                 "Rounds over every structure (medians reported, and bvh/embree-direct's lowest and highest round)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  add_runner(commands, rt, o, run_rt_bench);
}

void add_path_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<PathBenchOptions>();
  CLI::App* path = bench.add_subcommand(
      "path", "Path tracer Msamples/s and Mrays/s on the Cornell box, a yard lit by a sky map and CBbunny at "
              "512x512, on one thread and all; with --mitsuba, Mitsuba 3 scalar_rgb and llvm_ad_rgb (its JIT warm-up untimed, printed) on the same Cornell box and "
              "yard beside it");
  path->add_option("--job", o->cornell_job, "The Cornell box job")->capture_default_str();
  path->add_option("--assets", o->assets,
                   "The lab's assets folder, for CBbunny (default ../shared/assets)");
  add_thread_counts_option(*path, o->threads, "Thread counts (default: 1 and all)");
  add_spp_option(*path, o->spp);
  add_image_size_options(*path, o->width, o->height);
  path->add_option("--textured-job", o->textured_job, "The textured Cornell box job (for --scene textured)")
      ->capture_default_str();
  path->add_option("--environment-job", o->environment_job, "The job lit by a sky map (for --scene environment)")
      ->capture_default_str();
  path->add_option("--scene", o->scene,
                   "Which scene: cornell, textured (the textured Cornell box's cost per sample against "
                   "the plain one's), environment, cbbunny or all")
      ->check(CLI::IsMember({"cornell", "textured", "environment", "cbbunny", "all"}))
      ->capture_default_str();
  path->add_option("--mitsuba", o->mitsuba_python,
                   "A Python with the mitsuba package (see tools/requirements-mitsuba.txt): "
                   "time Mitsuba 3 scalar_rgb and llvm_ad_rgb on the Cornell box and the sky-lit yard too");
  path->add_option("--mitsuba-script", o->mitsuba_script,
                   "The script that renders a job with Mitsuba")
      ->capture_default_str();
  path->add_option("--repeats", o->repeats,
                   "Rounds, each rendering with farm and then each Mitsuba variant (medians reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  add_runner(commands, path, o, run_path_bench);
}

void add_farm_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<FarmBenchOptions>();
  CLI::App* farm = bench.add_subcommand(
      "farm", "The farm's overhead: the Cornell box path traced through farm render, a scheduler with 1 "
              "and with 2 workers over loopback; then tiny jobs for jobs/s and submit latency");
  farm->add_option("--job", o->job, "The job to render")->capture_default_str();
  add_spp_option(*farm, o->spp);
  add_image_size_options(*farm, o->width, o->height);
  farm->add_option("--repeats", o->repeats, "Renders per configuration (median reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  farm->add_option("--tiles-per-worker", o->tiles_per_worker,
                   "The scheduler's --tiles-per-worker for (b), (c) and the tiny jobs")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  farm->add_option("--batch-ms", o->batch_ms,
                   "The scheduler's --batch-ms for (a), (b), (c) and the tiny jobs (0: one tile a call)")
      ->check(CLI::Range(0, 600000))
      ->capture_default_str();
  farm->add_option("--two-worker-threads", o->two_worker_threads,
                   "--threads of each worker in (c) (0: all cores each, as `farm worker` defaults)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  farm->add_option("--tiny-jobs", o->tiny_jobs, "Tiny jobs to submit")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  farm->add_option("--store", o->store,
                   "A PostgreSQL job store, postgresql://USER@HOST:PORT/DATABASE: the tiny jobs run on it "
                   "too, beside SQLite (its jobs stay in it)")
      ->check([](const std::string& url) {
        return is_postgres_url(url) ? std::string() : "give a postgresql:// URL";
      });
  add_runner(commands, farm, o, run_farm_bench);
}

void add_render_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<RenderBenchOptions>();
  CLI::App* render = bench.add_subcommand(
      "render", "The whole `farm render` command (process start to exit) against the bare engine frame "
                "on the same scene: the lab's cow job and a 100-cow grid at 1920x1080, 1 and 2 threads; "
                "with the command's cores, kernel time (its page faults: on a VM, what moves most between "
                "runs) and peak memory");
  render->add_option("--cow-job", o->cow_job, "The cow job")->capture_default_str();
  render->add_option("--asset-root", o->asset_root, "The cow job's asset root")->capture_default_str();
  add_thread_counts_option(*render, o->threads, "Thread counts")->capture_default_str();
  render->add_option("--repeats", o->repeats, "Rounds (medians reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  add_cow_scene_option(*render, o->scene);
  add_runner(commands, render, o, run_render_bench);
}

void add_frames_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<FramesBenchOptions>();
  CLI::App* frames = bench.add_subcommand(
      "frames", "A frame range against its frames: the cow turntable (48 frames, raster, 1 thread) through "
                "`farm render` vs the engine's frames plus one model load; a 16-frame path animation on a "
                "scheduler with 1 and 2 workers");
  frames->add_option("--cow", o->cow, "The lab's cow.dae")->capture_default_str();
  frames->add_option("--path-job", o->path_job, "The path-traced animation")->capture_default_str();
  frames->add_option("--frames", o->frames, "Frames of the turntable")->check(CLI::Range(1, 1000))->capture_default_str();
  frames->add_option("--repeats", o->repeats, "Rounds (medians reported)")->check(CLI::Range(1, 100))->capture_default_str();
  frames->add_option("--scene", o->scene, "turntable, path or all")
      ->check(CLI::IsMember({"turntable", "path", "all"}))
      ->capture_default_str();
  add_runner(commands, frames, o, run_frames_bench);
}

void add_dispatch_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<DispatchBenchOptions>();
  CLI::App* dispatch = bench.add_subcommand(
      "dispatch", "The scheduler's choice of the next batch: claims timed on a SQLite store of 100 and of 10,000 "
                  "queued one-unit jobs of 50 owners");
  dispatch->add_option("--queued", o->queued, "Queue lengths, one run each")
      ->check(CLI::Range(1, 1000000))
      ->delimiter(',')
      ->capture_default_str();
  dispatch->add_option("--claims", o->claims, "Timed claims a run")->check(CLI::Range(1, 1000000))->capture_default_str();
  dispatch->add_option("--owners", o->owners, "The jobs' owners, round robin")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  add_runner(commands, dispatch, o, run_dispatch_bench);
}

void add_regress_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<RegressBenchOptions>();
  CLI::App* regress = bench.add_subcommand(
      "regress", "A regression suite on the embedded farm (--jobs 1 and 2) and through a scheduler with two "
                 "workers over loopback, taking turns; checks that all three give the same verdicts");
  regress->add_option("--suite", o->suite, "The suite")->capture_default_str();
  regress->add_option("--repeats", o->repeats, "Rounds (medians reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  regress->add_option("--worker-threads", o->worker_threads, "--threads of each worker")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  add_runner(commands, regress, o, run_regress_bench);
}

void add_flip_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<FlipBenchOptions>();
  CLI::App* flip = bench.add_subcommand(
      "flip", "`farm compare --metric flip` against NVIDIA's flip-evaluator on the same 1920x1080 pair (LDR and "
              "HDR) and thread count, whole commands taking turns");
  flip->add_option("--job", o->job, "The scene, rendered at 4 spp (reference) and 1 spp")->capture_default_str();
  add_image_size_options(*flip, o->width, o->height);
  add_thread_counts_option(*flip, o->threads, "Thread counts")->capture_default_str();
  flip->add_option("--repeats", o->repeats, "Runs of each command (median reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  flip->add_option("--python", o->python, "A Python with flip-evaluator (deploy/install-deps.sh makes this venv)")
      ->capture_default_str();
  add_runner(commands, flip, o, run_flip_bench);
}

void add_grade_bench(CLI::App& bench, CommandTable& commands) {
  auto o = std::make_shared<GradeBenchOptions>();
  CLI::App* grade = bench.add_subcommand(
      "grade", "A synthetic class graded by a rubric on the embedded farm: references rendered once, then every "
               "student");
  grade->add_option("--rubric", o->rubric, "The rubric")->capture_default_str();
  grade->add_option("--students", o->students, "Students in the class")->check(CLI::Range(1, 100000))->capture_default_str();
  grade->add_option("--jobs", o->jobs, "Students at a time (0: one per core)")->check(CLI::Range(0, 256))->capture_default_str();
  add_runner(commands, grade, o, run_grade_bench);
}

}  // namespace

void add_bench_command(CLI::App& app, CommandTable& commands) {
  CLI::App* bench = app.add_subcommand("bench", "Measure engine performance");
  bench->require_subcommand(1);
  add_raster_bench(*bench, commands);
  add_rt_bench(*bench, commands);
  add_path_bench(*bench, commands);
  add_farm_bench(*bench, commands);
  add_render_bench(*bench, commands);
  add_regress_bench(*bench, commands);
  add_frames_bench(*bench, commands);
  add_dispatch_bench(*bench, commands);
  add_flip_bench(*bench, commands);
  add_grade_bench(*bench, commands);
}

}  // namespace farm
