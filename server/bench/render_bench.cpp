#include "server/bench/render_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_support.h"
#include "server/common/child_process.h"
#include "server/common/read_whole_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using bench::median;
using bench::ms_since;

constexpr auto kCommandTimeout = std::chrono::minutes(5);

struct BenchJob {
  std::string name;
  fs::path file;
  JobLoadOptions load;
};

// The grid of bench::cow_grid as a job file: 10 x 10 cows 1.0 apart in x and 1.7 in z, each
// turned by its own angle, seen from above one end, lit by one light over the grid. The cow is
// copied beside the job, so the job's folder is its asset root as a user's would be.
BenchJob write_grid_job(const fs::path& cow_model, const fs::path& dir) {
  fs::copy_file(cow_model, dir / "cow.dae", fs::copy_options::overwrite_existing);
  constexpr int kSide = 10;
  constexpr float kDx = 1.0f, kDz = 1.7f, kExtent = kSide * kDz;
  nlohmann::json objects = nlohmann::json::array();
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      objects.push_back({{"file", "cow.dae"},
                         {"translate", {(static_cast<float>(i) - 0.5f * (kSide - 1)) * kDx, 0.0f,
                                        (static_cast<float>(j) - 0.5f * (kSide - 1)) * kDz}},
                         {"rotate", {{"axis", {0, 1, 0}}, {"degrees", (i * 37 + j * 11) % 360}}}});
    }
  }
  const nlohmann::json job = {
      {"version", 1},
      {"name", "cow_grid_100"},
      {"scene",
       {{"objects", objects},
        {"camera", {{"position", {0.0f, 0.75f * kExtent, 0.95f * kExtent}}, {"target", {0, 0, 0}},
                    {"far", 4.0f * kExtent}}},
        {"lights", {{{"position", {0.0f, kExtent, 0.3f * kExtent}}, {"intensity", kExtent * kExtent}}}}}},
      {"render", {{"engine", "raster"}, {"width", 1920}, {"height", 1080}}},
      {"output", {{"image", "out/cow_grid_100.exr"}, {"preview", "out/cow_grid_100.png"}}}};
  const fs::path file = dir / "cow_grid_100.json";
  std::ofstream(file) << job.dump(1) << '\n';
  return {"cow-grid-100", file, {}};
}

// One `farm render`: its time from process start to exit, the CPU time of all its threads, the
// kernel's part of it, and its peak resident memory.
struct CommandRun {
  double ms = 0.0, cpu_ms = 0.0, kernel_ms = 0.0, peak_mib = 0.0;
};

// One `farm render` of `job`, its outputs under `dir`.
CommandRun time_command(const BenchJob& job, int threads, const fs::path& dir) {
  std::vector<std::string> argv{bench::self_binary(), "render", job.file.string(), "--threads",
                                std::to_string(threads), "--quiet",
                                "--out", (dir / (job.name + ".exr")).string(),
                                "--preview", (dir / (job.name + ".png")).string()};
  if (!job.load.asset_root.empty()) {
    argv.insert(argv.end(), {"--asset-root", job.load.asset_root.string()});
  }
  const Clock::time_point start = Clock::now();
  ChildProcess command(argv);
  const std::optional<int> code = command.wait_exit(kCommandTimeout);
  const double ms = ms_since(start);
  if (code != 0) {
    throw std::runtime_error(fmt::format("farm render {} failed ({}): {}", job.file.string(),
                                         code ? fmt::format("exit {}", *code) : "timed out",
                                         command.output()));
  }
  return {ms, command.cpu_seconds().value_or(0.0) * 1e3, command.kernel_seconds().value_or(0.0) * 1e3,
          static_cast<double>(command.peak_memory_bytes().value_or(0)) / (1024.0 * 1024.0)};
}

// The engine alone: render_frame on an already loaded scene, a fresh PreparedScene for each frame
// (as `farm bench raster` does) so the engine's per-frame set-up is counted, a pool made once.
double time_engine_frame(const Scene& scene, RenderSettings settings, int threads, ThreadPool& pool) {
  settings.threads = threads;
  const PreparedScene prepared{Scene(scene)};
  TileBuffer film;
  FrameTimings timings;
  render_frame(prepared, settings, pool, film, {}, &timings);
  return timings.total_ms;
}

void bench_job(const BenchJob& job, const RenderBenchOptions& o, const fs::path& out_dir) {
  const Job parsed = load_job(job.file, job.load);
  const Scene scene = build_scene(parsed);
  const RenderSettings& r = parsed.render;
  fmt::print("\n{}: {} engine, {}x{}, {} triangles in {} object(s), median of {} rounds\n", job.name,
             to_string(r.engine), r.width, r.height, scene.triangle_count(), scene.objects.size(),
             o.repeats);
  fmt::print("{:>7} {:>14} {:>15} {:>8} {:>22} {:>7} {:>10} {:>9}\n", "threads", "engine frame", "farm render",
             "ratio", "2 x frame + 100 ms", "cores", "kernel", "peak");
  // One pool per thread count, each warmed up (caches, page faults) with a frame and a command.
  std::map<int, std::unique_ptr<ThreadPool>> pools;
  for (int threads : o.threads) {
    auto& pool = pools[threads];
    if (pool) continue;
    pool = std::make_unique<ThreadPool>(threads);
    time_engine_frame(scene, r, threads, *pool);
    time_command(job, threads, out_dir);
  }
  // Each round times every thread count in turn, the order reversed every other round, so that a
  // change in a shared machine's state (its load; on a VM, whether freed memory must come back
  // from the host) falls on all of them alike; within a count, the engine frame and the command
  // take turns too. The speedups are paired by round.
  struct Runs {
    std::vector<double> engine, command, ratio, cores, kernel, peak;
  };
  std::map<int, Runs> runs;
  std::vector<int> order;  // each count once, fewest threads first
  for (const auto& entry : pools) order.push_back(entry.first);
  for (int i = 0; i < o.repeats; ++i) {
    for (int threads : order) {
      Runs& r_t = runs[threads];
      r_t.engine.push_back(time_engine_frame(scene, r, threads, *pools.at(threads)));
      const CommandRun run = time_command(job, threads, out_dir);
      r_t.command.push_back(run.ms);
      r_t.ratio.push_back(run.ms / r_t.engine.back());
      // cores: the command's CPU time over its time, what it kept busy on average.
      r_t.cores.push_back(run.cpu_ms / run.ms);
      // kernel: its system time, where a fresh process's page faults (the kernel zeroing every
      // new page) go; on a VM they can cost several times more when the host must back the
      // memory first, and that is what moves this table most from one run to the next.
      r_t.kernel.push_back(run.kernel_ms);
      r_t.peak.push_back(run.peak_mib);
    }
    std::reverse(order.begin(), order.end());
  }
  for (const auto& [threads, r_t] : runs) {
    const double e = median(r_t.engine), c = median(r_t.command);
    const double bound = 2.0 * e + 100.0;
    fmt::print("{:>7} {:>11.1f} ms {:>12.1f} ms {:>7.1f}x {:>12.1f} ms ({}) {:>7.2f} {:>7.1f} ms {:>5.0f} MiB\n",
               threads, e, c, median(r_t.ratio), bound, c <= bound ? "within" : "over", median(r_t.cores),
               median(r_t.kernel), median(r_t.peak));
  }
  if (runs.size() > 1) {
    const auto first = runs.begin();
    for (auto it = std::next(first); it != runs.end(); ++it) {
      std::vector<double> speedups;
      for (std::size_t i = 0; i < it->second.command.size(); ++i) {
        speedups.push_back(first->second.command[i] / it->second.command[i]);
      }
      fmt::print("whole-command speedup {} -> {} threads: {:.2f}x (paired by round, median; of the medians: {:.2f}x)\n",
                 first->first, it->first, median(speedups), median(first->second.command) / median(it->second.command));
    }
  }
}

}  // namespace

void run_render_bench(const RenderBenchOptions& o) {
  if (!fs::exists(o.cow_job)) {
    throw InputError(fmt::format("{}: no such job (pass --cow-job PATH to jobs/cow.json)", o.cow_job.string()));
  }
  BenchJob cow{"cow", o.cow_job, {.asset_root = o.asset_root, .asset_root_hint = {}}};
  const Job cow_job = load_job(cow.file, cow.load);
  const bench::ScratchDir scratch("bench-render");
  const fs::path& dir = scratch.path();
  fmt::print("farm bench render ({}): the whole `farm render` command "
             "(process start to exit) vs the bare engine frame on the same scene\n",
             bench::machine_summary());
  if (o.scene == "all" || o.scene == "cow") bench_job(cow, o, dir);
  if (o.scene == "all" || o.scene == "cow-grid-100") {
    bench_job(write_grid_job(cow_job.scene.objects.at(0).file, dir), o, dir);
  }
}

}  // namespace farm
