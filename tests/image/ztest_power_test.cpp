// The z-test's size and power on real renders: the path-traced Cornell box at 20 pairs of seeds
// (the same scene, only the noise differs) fails at most once at alpha 0.01; the same renders 2%
// darker fail every time; a rasterised image shifted by one pixel fails. The images go through
// half EXRs, as `farm regress` compares them.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstdio>

#include "renderer/accel/prepared_scene.h"
#include "renderer/compare/compare.h"
#include "renderer/image/exr_io.h"
#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/render_frame.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

TileBuffer render_film(const PreparedScene& scene, RenderSettings settings, std::uint64_t seed) {
  settings.seed = seed;
  return render_frame(scene, settings);
}

// Through a half EXR and back, as `farm regress` reads a render.
Image as_stored(const TileBuffer& film, const fs::path& file) {
  write_exr(film, file);
  return read_image(file);
}

// The same render with every colour `gain` times as bright: what a lamp that much dimmer gives
// (light transport is linear); the variance of the mean scales with the square.
void scale(TileBuffer& film, float gain) {
  const Rect& r = film.rect();
  for (int y = r.y0; y < r.y1; ++y)
    for (int x = r.x0; x < r.x1; ++x) {
      glm::vec4& c = film.rgba(x, y);
      c = glm::vec4(glm::vec3(c) * gain, c.w);
      film.variance(x, y) *= gain * gain;
    }
}

TEST(ZtestPower, SeedsPassAtTheExpectedRateAndATwoPercentBiasAlwaysFails) {
  test::TempDir dir;
  Job job = load_job(fs::path(FARM_SOURCE_DIR) / "jobs/cornell_path.json");
  // Small and shallow (direct light only), so 40 renders take seconds, yet enough samples
  // (64x64 at 128 spp) that each channel mean's standard error is well under the 2% to find.
  job.render.width = 64;
  job.render.height = 64;
  job.render.spp = 128;
  job.render.max_depth = 1;
  job.render.aovs = {};
  job.render.aovs.add(Aov::Variance);
  const PreparedScene scene(build_scene(job));
  CompareSettings settings;
  settings.metric = Metric::ztest;
  int seed_failures = 0, bias_failures = 0;
  constexpr int kPairs = 20;
  for (int i = 0; i < kPairs; ++i) {
    const Image a = as_stored(render_film(scene, job.render, 100 + 2 * i), dir / "a.exr");
    TileBuffer b_film = render_film(scene, job.render, 101 + 2 * i);
    const Image b = as_stored(b_film, dir / "b.exr");
    scale(b_film, 0.98f);
    const Image darker = as_stored(b_film, dir / "d.exr");
    const CompareResult same = compare_images(a, b, settings), biased = compare_images(a, darker, settings);
    std::printf("pair %2d: seeds %s (mean z %+.2f, %.2f%% pass)   2%% darker %s (mean z %+.2f)\n", i,
                std::string(to_string(same.verdict)).c_str(), same.figure("mean_z"), same.figure("pass_percent"),
                std::string(to_string(biased.verdict)).c_str(), biased.figure("mean_z"));
    seed_failures += same.verdict == Verdict::fail;
    bias_failures += biased.verdict == Verdict::fail;
  }
  EXPECT_LE(seed_failures, 1) << "the same scene at different seeds must pass (alpha 0.01)";
  EXPECT_EQ(bias_failures, kPairs) << "a 2% darker image must fail every time";
}

TEST(ZtestPower, ARasterImageShiftedByOnePixelFails) {
  test::TempDir dir;
  Job job = load_job(fs::path(FARM_SOURCE_DIR) / "jobs/cornell.json");
  job.render.width = 64;
  job.render.height = 64;
  job.render.aovs = {};
  job.render.aovs.add(Aov::Variance);  // zeros: the rasterizer is deterministic
  const PreparedScene scene(build_scene(job));
  const Image a = as_stored(render_film(scene, job.render, 0), dir / "a.exr");
  Image shifted = a;
  for (int y = 0; y < a.height; ++y)
    for (int x = 1; x < a.width; ++x)
      for (int c = 0; c < static_cast<int>(a.channel_count()); ++c) shifted.at(x, y, c) = a.at(x - 1, y, c);
  CompareSettings settings;
  settings.metric = Metric::ztest;
  EXPECT_EQ(compare_images(a, a, settings).verdict, Verdict::pass);
  const CompareResult r = compare_images(a, shifted, settings);
  EXPECT_EQ(r.verdict, Verdict::fail) << r.summary;
  std::printf("shifted raster: %s\n", r.summary.c_str());
}

}  // namespace
}  // namespace farm
