#include "server/bench/flip_bench.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>

#include "renderer/accel/prepared_scene.h"
#include "renderer/image/exr_io.h"
#include "renderer/image/preview.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "server/bench/bench_support.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The wall time of one shell command; throws when it fails (its output is in the message).
double time_command(const std::string& command) {
  const Clock::time_point start = Clock::now();
  const int status = std::system((command + " > /dev/null 2>&1").c_str());
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  // farm compare exits 1 on FAIL, which a noisy pair may well be; anything else is a failure.
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) > 1) {
    throw std::runtime_error(fmt::format("`{}` failed (status {})", command, status));
  }
  return seconds;
}

void render_pair(const FlipBenchOptions& o, const fs::path& dir) {
  Job job = load_job(o.job);
  job.render.width = o.width;
  job.render.height = o.height;
  job.render.aovs = {};
  const PreparedScene scene(build_scene(job));
  for (const auto& [name, spp] : {std::pair{"ref", 4}, std::pair{"new", 1}}) {
    RenderSettings settings = job.render;
    settings.spp = spp;
    const TileBuffer film = render_frame(scene, settings);
    write_exr(film, dir / fmt::format("{}.exr", name));
    write_preview(film, dir / fmt::format("{}.png", name));
  }
}

}  // namespace

void run_flip_bench(const FlipBenchOptions& o) {
  const bench::ScratchDir scratch("bench-flip");
  const fs::path& dir = scratch.path();
  render_pair(o, dir);
  const std::string farm = bench::self_binary();
  fmt::print("farm bench flip ({}): {} at {}x{}, 4 spp vs 1 spp; whole commands, "
             "median of {}, taking turns\n",
             bench::machine_summary(), o.job.string(), o.width, o.height, o.repeats);
  fmt::print("{:<5} {:>8} {:>16} {:>16} {:>10}\n", "range", "threads", "farm compare", "flip-evaluator", "speed-up");
  for (const char* range : {"LDR", "HDR"}) {
    const std::string ext = std::string(range) == "LDR" ? "png" : "exr";
    const std::string ref = (dir / ("ref." + ext)).string(), fresh = (dir / ("new." + ext)).string();
    for (int threads : o.threads) {
      const std::string ours = fmt::format("'{}' compare --metric flip --threads {} '{}' '{}'", farm, threads, ref, fresh);
      const std::string theirs = fmt::format(
          "OMP_NUM_THREADS={} '{}' -c 'import sys, flip_evaluator as f; f.evaluate(sys.argv[1], sys.argv[2], sys.argv[3])' "
          "'{}' '{}' {}",
          threads, o.python, ref, fresh, range);
      std::vector<double> a, b;
      for (int i = 0; i < o.repeats; ++i) {
        a.push_back(time_command(ours));
        b.push_back(time_command(theirs));
      }
      const double ma = bench::median(a), mb = bench::median(b);
      fmt::print("{:<5} {:>8} {:>14.3f} s {:>14.3f} s {:>9.1f}x\n", range, threads, ma, mb, mb / ma);
    }
  }
}

}  // namespace farm
