#include "server/bench/frames_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_support.h"
#include "server/bench/loopback_farm.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/child_process.h"
#include "server/scheduler/jobs/job_merger.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using bench::median;
using bench::ms_since;

constexpr auto kCommandTimeout = std::chrono::minutes(10);

// The cow on a turntable: one full turn over `frames` frames, the lab's camera and light.
fs::path write_turntable(const fs::path& cow, const fs::path& dir, int frames) {
  fs::copy_file(cow, dir / "cow.dae", fs::copy_options::overwrite_existing);
  const nlohmann::json job = {
      {"version", 1},
      {"name", "cow_turntable"},
      {"frames", {{"start", 1}, {"end", frames}}},
      {"scene",
       {{"objects", {{{"file", "cow.dae"}, {"rotate", {{"axis", {0, 1, 0}}, {"degrees", 0}}}}}},
        {"camera", {{"position", {2, 2, 2}}, {"target", {0, 0, 0}}}},
        {"lights", {{{"position", {2, 2, 2}}, {"intensity", 10}}}}}},
      {"animate",
       {{{"value", "scene.objects[0].rotate.degrees"},
         {"keys", {{{"frame", 1}, {"value", 0}}, {{"frame", frames + 1}, {"value", 360}}}}}}},
      {"render", {{"engine", "raster"}, {"width", 640}, {"height", 480}, {"threads", 1}}},
      {"output", {{"image", (dir / "out" / "cow.####.exr").string()}, {"preview", (dir / "out" / "cow.####.png").string()}}}};
  const fs::path file = dir / "cow_turntable.json";
  std::ofstream(file) << job.dump(1) << '\n';
  return file;
}

double time_render_command(const fs::path& job) {
  const Clock::time_point start = Clock::now();
  ChildProcess command({bench::self_binary(), "render", job.string(), "--threads", "1", "--quiet"});
  const std::optional<int> code = command.wait_exit(kCommandTimeout);
  const double ms = ms_since(start);
  if (code != 0) throw std::runtime_error(fmt::format("farm render {} failed: {}", job.string(), command.output()));
  return ms;
}

// One model load, as the farm does it once per job.
double time_model_load(const fs::path& model) {
  const Clock::time_point start = Clock::now();
  const Model m = load_model(model);
  const double ms = ms_since(start);
  if (m.triangle_count() == 0) throw std::runtime_error("the cow has no triangles");
  return ms;
}

// The engine alone over every frame: each frame's scene built from models loaded once, a fresh
// PreparedScene each (so the per-frame set-up is counted), rendered on one thread. Apart, what
// writing each frame's files (half EXR and PNG, as `farm render` writes them) takes.
struct EngineFrames {
  double render_ms = 0.0;
  double write_ms = 0.0;
};

EngineFrames time_engine_frames(const Job& job, ThreadPool& pool, const fs::path& dir) {
  ModelLibrary models(job.asset_root);
  build_scene(job, models);  // the load, not counted here: time_model_load measures it
  EngineFrames total;
  TileBuffer film;
  for (int frame : job_frames(job)) {
    const Job at = job_at_frame(job, frame);
    const PreparedScene prepared(build_scene(at, models));
    FrameTimings timings;
    render_frame(prepared, at.render, pool, film, {}, &timings);
    total.render_ms += timings.total_ms;
    const Clock::time_point start = Clock::now();
    write_merged(film, {dir / "engine.exr", dir / "engine.png"});
    total.write_ms += ms_since(start);
  }
  return total;
}

void bench_turntable(const FramesBenchOptions& o, const fs::path& dir) {
  if (!fs::exists(o.cow)) throw InputError(fmt::format("{}: no such model (pass --cow PATH to cow.dae)", o.cow.string()));
  const fs::path file = write_turntable(o.cow, dir, o.frames);
  const Job job = load_job(file);
  fmt::print("\nturntable: the cow, {} frames at {}x{}, raster, 1 thread, median of {} rounds\n", o.frames,
             job.render.width, job.render.height, o.repeats);
  ThreadPool pool(1);
  time_engine_frames(job, pool, dir);  // warm-up
  time_render_command(file);
  std::vector<double> engine, writes, load, command, ratio, beyond_writes;
  for (int i = 0; i < o.repeats; ++i) {
    const EngineFrames frames = time_engine_frames(job, pool, dir);
    engine.push_back(frames.render_ms);
    writes.push_back(frames.write_ms);
    load.push_back(time_model_load(job.scene.objects[0].file));
    command.push_back(time_render_command(file));
    ratio.push_back(command.back() / (engine.back() + load.back()));
    beyond_writes.push_back(command.back() / (engine.back() + load.back() + writes.back()));
  }
  const double e = median(engine), w = median(writes), l = median(load), c = median(command);
  fmt::print("{:<48} {:>10.1f} ms ({:.2f} ms a frame)\n", fmt::format("engine, {} frames", o.frames), e, e / o.frames);
  fmt::print("{:<48} {:>10.1f} ms ({:.2f} ms a frame)\n", "writing them (half EXR + PNG), one after another", w,
             w / o.frames);
  fmt::print("{:<48} {:>10.1f} ms\n", "one model load", l);
  fmt::print("{:<48} {:>10.1f} ms\n", "farm render of the whole job (start to exit)", c);
  fmt::print("whole job / (engine frames + one load): {:.3f} (paired by round, median); target <= 1.5: {}\n",
             median(ratio), median(ratio) <= 1.5 ? "within" : "over");
  fmt::print("whole job / (engine frames + writing them + one load): {:.3f} (the farm's own cost beyond both)\n",
             median(beyond_writes));
}

void bench_path(const FramesBenchOptions& o, const fs::path& dir) {
  const JobSubmission submission = make_job_submission(o.path_job, {}, {});
  const Job& job = submission.job;
  fmt::print("\npath: {}, {} frames at {}x{}, {} spp, median of {} rounds\n", o.path_job.string(),
             job_frames(job).size(), job.render.width, job.render.height, job.render.spp, o.repeats);
  // Two workers on one machine either share its cores (half each: the machine's threads, as one
  // worker has them) or each take them all (twice as many threads as cores, contending).
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bench::LoopbackFarm one(dir / "one", 1, 2, 200, 0);
  bench::LoopbackFarm shared(dir / "shared", 2, 2, 200, std::max(1, cores / 2));
  bench::LoopbackFarm contending(dir / "contending", 2, 2, 200, 0);
  SchedulerClient client_one(one.address()), client_shared(shared.address()), client_contending(contending.address());
  std::vector<double> a, b, c, ratio_shared, ratio_contending;
  for (int i = 0; i < o.repeats; ++i) {
    a.push_back(1e3 * bench::submit_and_wait(client_one, submission).second);
    b.push_back(1e3 * bench::submit_and_wait(client_shared, submission).second);
    c.push_back(1e3 * bench::submit_and_wait(client_contending, submission).second);
    ratio_shared.push_back(a.back() / b.back());
    ratio_contending.push_back(a.back() / c.back());
  }
  const auto threads = [](int n) { return fmt::format("{} thread{}", n, n == 1 ? "" : "s"); };
  fmt::print("{:<48} {:>10.1f} ms\n", fmt::format("scheduler + 1 worker ({})", threads(cores)), median(a));
  fmt::print("{:<48} {:>10.1f} ms\n", fmt::format("scheduler + 2 workers ({} each)", threads(std::max(1, cores / 2))),
             median(b));
  fmt::print("{:<48} {:>10.1f} ms\n", fmt::format("scheduler + 2 workers ({} each)", threads(cores)), median(c));
  fmt::print("2 workers sharing the cores: {:.2f}x the speed of 1 (paired by round, median); target >= 1.0: {}\n",
             median(ratio_shared), median(ratio_shared) >= 1.0 ? "met" : "below it");
  fmt::print("2 workers with every core each: {:.2f}x the speed of 1 (paired by round, median)\n",
             median(ratio_contending));
}

}  // namespace

void run_frames_bench(const FramesBenchOptions& o) {
  const bench::ScratchDir scratch("bench-frames");
  fmt::print("farm bench frames ({})\n", bench::machine_summary());
  if (o.scene == "all" || o.scene == "turntable") bench_turntable(o, scratch.path());
  if (o.scene == "all" || o.scene == "path") bench_path(o, scratch.path());
}

}  // namespace farm
