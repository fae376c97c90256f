#include "server/bench/path_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "renderer/scene/model.h"
#include "renderer/util/input_error.h"
#include "server/bench/bench_scenes.h"
#include "server/bench/bench_support.h"

namespace farm {
namespace {

using Clock = std::chrono::steady_clock;

struct Throughput {
  double seconds = 0.0;
  double samples = 0.0;
  double rays = 0.0;
  double msamples_per_s() const { return samples / seconds / 1e6; }
  double mrays_per_s() const { return rays / seconds / 1e6; }
};

// One untimed frame at 1 spp first, so the BVH and emitter table are built outside the timing.
Throughput measure(const PreparedScene& scene, RenderSettings settings, int threads) {
  settings.threads = threads;
  ThreadPool pool(threads);
  TileBuffer film;
  RenderSettings warm = settings;
  warm.spp = 1;
  render_frame(scene, warm, pool, film);
  const Clock::time_point start = Clock::now();
  render_frame(scene, settings, pool, film);
  Throughput t;
  t.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  t.samples = static_cast<double>(film.stats().samples);
  t.rays = static_cast<double>(film.stats().rays);
  return t;
}

// The Mitsuba variants timed beside ours: the scalar one, and the vectorised JIT one on LLVM
// (Mitsuba's fastest on a CPU), which compiles its kernels in an untimed first render.
constexpr std::array<const char*, 2> kMitsubaVariants = {"scalar_rgb", "llvm_ad_rgb"};

// Runs tools/mitsuba_reference.py --bench --warmup on `job` in `variant` and reads its one JSON
// line; a Mitsuba that has not answered in 15 minutes is stopped. `warmup_seconds`: the untimed
// first render's time.
std::optional<Throughput> measure_mitsuba(const PathBenchOptions& o, const std::filesystem::path& job, int threads,
                                          const char* variant, std::string& renderer, double& warmup_seconds) {
  const std::string command = fmt::format(
      "timeout 900 '{}' '{}' '{}' --width {} --height {} --spp {} --threads {} --variant {} --bench --warmup 2>&1",
      o.mitsuba_python, o.mitsuba_script.string(), job.string(), o.width, o.height, o.spp, threads, variant);
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(command.c_str(), "r"), pclose);
  if (!pipe) return std::nullopt;
  std::string output;
  std::array<char, 4096> buffer{};
  while (fgets(buffer.data(), buffer.size(), pipe.get()) != nullptr) output += buffer.data();
  const auto brace = output.rfind('{');
  const auto parsed = brace == std::string::npos ? nlohmann::json() : nlohmann::json::parse(output.substr(brace), nullptr, false);
  if (!parsed.is_object() || !parsed.contains("seconds")) {
    fmt::print("  mitsuba did not run: {}\n", output.substr(0, 400));
    return std::nullopt;
  }
  renderer = parsed.value("renderer", "mitsuba");
  warmup_seconds = parsed.value("warmup_seconds", 0.0);
  Throughput t;
  t.seconds = parsed["seconds"].get<double>();
  t.samples = static_cast<double>(o.width) * o.height * o.spp;
  return t;
}

// One Mitsuba variant's rounds at one thread count.
struct MitsubaRounds {
  std::string renderer;  // as its script names itself
  std::vector<Throughput> rounds;
  std::vector<double> warmups;  // its untimed first render's seconds, each round
};

// The rounds' median time. Samples and rays are the same every round: the same image, seeded alike.
Throughput median_of(const std::vector<Throughput>& rounds) {
  std::vector<double> seconds;
  for (const Throughput& t : rounds) seconds.push_back(t.seconds);
  Throughput m = rounds.front();
  m.seconds = bench::median(seconds);
  return m;
}

// `mitsuba_job`: the job Mitsuba renders beside ours; empty: none. Each round renders with farm
// and then with each Mitsuba variant, so that a slow spell of a shared machine falls on all of
// them alike; the medians over rounds are printed.
void bench_scene(const std::string& name, const PreparedScene& scene, RenderSettings settings,
                 const PathBenchOptions& o, const std::filesystem::path& mitsuba_job) {
  settings.engine = EngineKind::Path;
  settings.width = o.width;
  settings.height = o.height;
  settings.spp = o.spp;
  settings.aovs = {};
  const bool with_mitsuba = !mitsuba_job.empty() && !o.mitsuba_python.empty();
  fmt::print("\nscene {}: {} triangles, {}x{}, {} spp, max_depth {}{}\n", name, scene.triangle_count(), o.width,
             o.height, o.spp, settings.max_depth,
             o.repeats > 1 ? fmt::format(", median of {} rounds{}", o.repeats,
                                         with_mitsuba ? " (farm and Mitsuba taking turns)" : "")
                           : std::string());
  fmt::print("{:<28} {:>7} {:>9} {:>11} {:>9} {:>11} {:>8}\n", "renderer", "threads", "seconds",
             "Msamples/s", "Mrays/s", "rays/sample", "speedup");
  double single = 0.0;
  for (int threads : o.threads) {
    std::vector<Throughput> farm_rounds;
    std::array<MitsubaRounds, kMitsubaVariants.size()> mitsuba;
    for (int round = 0; round < o.repeats; ++round) {
      farm_rounds.push_back(measure(scene, settings, threads));
      if (!with_mitsuba) continue;
      for (std::size_t v = 0; v < kMitsubaVariants.size(); ++v) {
        double warmup = 0.0;
        if (const auto m = measure_mitsuba(o, mitsuba_job, threads, kMitsubaVariants[v], mitsuba[v].renderer, warmup)) {
          mitsuba[v].rounds.push_back(*m);
          mitsuba[v].warmups.push_back(warmup);
        }
      }
    }
    const Throughput t = median_of(farm_rounds);
    if (threads == 1) single = t.msamples_per_s();
    fmt::print("{:<28} {:>7} {:>9.2f} {:>11.3f} {:>9.2f} {:>11.2f} {:>7.2f}x\n", "farm path", threads,
               t.seconds, t.msamples_per_s(), t.mrays_per_s(), t.rays / t.samples,
               single > 0.0 ? t.msamples_per_s() / single : 0.0);
    for (const MitsubaRounds& m : mitsuba) {
      if (m.rounds.empty()) continue;
      const Throughput mt = median_of(m.rounds);
      fmt::print("{:<28} {:>7} {:>9.2f} {:>11.3f} {:>9} {:>11} {:>8}   farm/mitsuba {:.2f}x (untimed warm-up {:.2f} s)\n",
                 m.renderer, threads, mt.seconds, mt.msamples_per_s(), "-", "-", "-",
                 t.msamples_per_s() / mt.msamples_per_s(), bench::median(m.warmups));
    }
  }
}

// The textured Cornell box against the plain one, the same room with a checker on its floor and
// back wall: frames taking turns (plain, textured, three times), best of each, and the cost of a
// textured sample as a ratio.
void bench_textured_pair(const PathBenchOptions& o) {
  const Job plain_job = load_job(o.cornell_job), textured_job = load_job(o.textured_job);
  const PreparedScene plain(build_scene(plain_job)), textured(build_scene(textured_job));
  RenderSettings settings = plain_job.render;
  settings.engine = EngineKind::Path;
  settings.width = o.width;
  settings.height = o.height;
  settings.spp = o.spp;
  settings.aovs = {};
  fmt::print("\nscene cornell ({}) against cornell textured ({}): {}x{}, {} spp, turns of each\n",
             o.cornell_job.string(), o.textured_job.string(), o.width, o.height, o.spp);
  fmt::print("{:<10} {:>7} {:>16} {:>19} {:>22}\n", "threads", "turns", "plain Msamples/s", "textured Msamples/s",
             "textured time/sample");
  for (int threads : o.threads) {
    double best_plain = 0.0, best_textured = 0.0;
    constexpr int kTurns = 3;
    for (int turn = 0; turn < kTurns; ++turn) {
      best_plain = std::max(best_plain, measure(plain, settings, threads).msamples_per_s());
      best_textured = std::max(best_textured, measure(textured, settings, threads).msamples_per_s());
    }
    fmt::print("{:<10} {:>7} {:>16.3f} {:>19.3f} {:>21.3f}x\n", threads, kTurns, best_plain, best_textured,
               best_plain / best_textured);
  }
}

}  // namespace

void run_path_bench(const PathBenchOptions& options) {
  PathBenchOptions o = options;
  if (o.threads.empty()) {
    o.threads = {1};
    const int all = resolve_thread_count(0);
    if (all > 1) o.threads.push_back(all);
  }
  if (o.assets.empty()) o.assets = "../shared/assets";
  fmt::print("farm bench path ({})\n", bench::machine_summary());

  if (o.scene == "all" || o.scene == "cornell") {
    const Job job = load_job(o.cornell_job);
    const PreparedScene scene(build_scene(job));
    bench_scene(fmt::format("cornell ({})", o.cornell_job.string()), scene, job.render, o, o.cornell_job);
  }
  if (o.scene == "all" || o.scene == "environment") {
    const Job job = load_job(o.environment_job);
    const PreparedScene scene(build_scene(job));
    bench_scene(fmt::format("environment ({}, lit by its map alone)", o.environment_job.string()), scene, job.render,
                o, o.environment_job);
  }
  if (o.scene == "all" || o.scene == "textured") bench_textured_pair(o);
  if (o.scene == "all" || o.scene == "cbbunny") {
    const std::filesystem::path path = o.assets / "dae" / "CBbunny.dae";
    if (!std::filesystem::exists(path)) {
      throw InputError(fmt::format("{}: no such model (pass --assets to the lab's assets folder)", path.string()));
    }
    const PreparedScene scene(bench::cbbunny_area_lit(load_model(path)));
    RenderSettings settings;
    settings.max_depth = -1;
    bench_scene("CBbunny (ceiling lamp emissive)", scene, settings, o, {});
  }
}

}  // namespace farm
