// Sample passes (issue #17): a frame's samples split into passes that any worker may render as
// (frame, tile, pass) units, merged in sample order by PassAccumulator into the same bits however
// the units were spread, and a progressive preview after every pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "renderer/engine.h"
#include "renderer/image/pass_merge.h"
#include "renderer/render_frame.h"
#include "renderer/util/input_error.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/scene_fixtures.h"

namespace farm {
namespace {

RenderSettings path_settings(int width, int height, int spp, int pass_spp) {
  RenderSettings s = test::raster_settings(width, height);
  s.engine = EngineKind::Path;
  s.spp = spp;
  s.pass_spp = pass_spp;
  s.max_depth = -1;  // unbounded: Russian roulette ends the paths
  s.seed = 11;
  s.aovs.depth = s.aovs.normal = s.aovs.albedo = s.aovs.bvh_cost = s.aovs.variance = true;
  return s;
}

// A glossy floor, a glass sphere and an area light: noisy everywhere, with edges for coverage.
PreparedScene glossy_glass_scene() {
  Material light;
  light.emission = glm::vec3(4.0f);
  Material glossy;
  glossy.diffuse = {0.6f, 0.3f, 0.2f};
  glossy.specular = glm::vec3(0.3f);
  glossy.shininess = 60;
  Material glass;
  glass.transmission = 1;
  glass.ior = 1.5f;
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_box({-3, -1.6f, -3}, {3, -1.2f, 3}), glm::mat4(1.0f), glossy));
  scene.objects.push_back(test::object_of(test::make_sphere(16, 32), glm::mat4(1.0f), glass));
  scene.objects.push_back(test::object_of(test::make_quad({-1, 3, -1}, {1, 3, -1}, {1, 3, 1}, {-1, 3, 1}), glm::mat4(1.0f), light));
  scene.lights.push_back(Light{Light::Kind::Point, {2, 3, 2}, {}, glm::vec3(6.0f)});
  scene.camera.position = {2.5f, 1.5f, 3.5f};
  scene.camera.far = 50;
  return PreparedScene(std::move(scene));
}

// A lamp whose radiance is NaN in red next to a sane one: samples that see it are invalid.
PreparedScene scene_with_a_bad_lamp() {
  Material bad;
  bad.emission = {std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f};
  Material good;
  good.emission = glm::vec3(1.0f);
  Scene scene;
  scene.objects.push_back(test::object_of(test::make_quad({-2, -1, 0}, {0, -1, 0}, {0, 1, 0}, {-2, 1, 0}), glm::mat4(1.0f), bad));
  scene.objects.push_back(test::object_of(test::make_quad({0, -1, 0}, {2, -1, 0}, {2, 1, 0}, {0, 1, 0}), glm::mat4(1.0f), good));
  scene.background = glm::vec3(0.0f);
  scene.camera.position = {0, 0, 3};
  scene.camera.target = {0, 0, 0};
  scene.camera.fov_y_degrees = 40;
  return PreparedScene(std::move(scene));
}

bool same_stats(const RenderStats& a, const RenderStats& b) {
  return a.fragments == b.fragments && a.samples == b.samples && a.invalid_samples == b.invalid_samples &&
         a.rays == b.rays;
}

// One pass of the whole frame, rendered as tiles of `tile_size` in `order` (tile indices).
std::vector<TileBuffer> render_pass_tiles(const PreparedScene& scene, RenderSettings settings, int pass,
                                          int tile_size, bool reversed) {
  settings.pass = pass;
  std::vector<Rect> tiles = split_into_tiles(settings.width, settings.height, tile_size);
  if (reversed) std::reverse(tiles.begin(), tiles.end());
  std::vector<TileBuffer> out(tiles.size());
  for (std::size_t i = 0; i < tiles.size(); ++i) render_tile(scene, settings, tiles[i], out[i]);
  return out;
}

// --- Pass ranges ---

TEST(SamplePassRanges, CoverEverySampleOnceInOrderWithAShortLastPass) {
  RenderSettings s = path_settings(8, 8, 40, 16);
  ASSERT_EQ(pass_count(s), 3);
  EXPECT_EQ(pass_samples(s, 0), (SampleRange{0, 16}));
  EXPECT_EQ(pass_samples(s, 1), (SampleRange{16, 32}));
  EXPECT_EQ(pass_samples(s, 2), (SampleRange{32, 40}));  // the remainder
  for (int spp : {1, 7, 16, 17, 63, 64, 65}) {
    for (int pass_spp : {1, 3, 16}) {
      s.spp = spp;
      s.pass_spp = pass_spp;
      const int passes = pass_count(s);
      EXPECT_EQ(passes, (spp + pass_spp - 1) / pass_spp) << spp << " / " << pass_spp;
      int next = 0;
      for (int p = 0; p < passes; ++p) {
        const SampleRange r = pass_samples(s, p);
        EXPECT_EQ(r.begin, next) << "pass " << p << " follows the one before";
        EXPECT_GE(r.count(), 1);
        EXPECT_LE(r.count(), pass_spp);
        next = r.end;
      }
      EXPECT_EQ(next, spp) << "the passes' samples add up to spp";
    }
  }
}

TEST(SamplePassRanges, NoPassSppOrAtLeastSppIsOnePassOfAllSamples) {
  for (int pass_spp : {0, 24, 25, 1000}) {
    RenderSettings s = path_settings(8, 8, 24, pass_spp);
    EXPECT_EQ(pass_count(s), 1) << pass_spp;
    EXPECT_EQ(pass_samples(s, 0), (SampleRange{0, 24})) << pass_spp;
    EXPECT_EQ(samples_to_render(s), (SampleRange{0, 24})) << "pass -1 is all samples";
  }
  RenderSettings s = path_settings(8, 8, 0, 4);  // spp below 1 renders one sample, as the engines do
  EXPECT_EQ(pass_count(s), 1);
  EXPECT_EQ(pass_samples(s, 0), (SampleRange{0, 1}));
}

TEST(SamplePassRanges, RasterAndWhittedRenderAllSamplesInTheirOnePass) {
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    RenderSettings s = path_settings(8, 8, 16, 4);
    s.engine = engine;
    EXPECT_EQ(pass_count(s), 1) << to_string(engine);
    EXPECT_EQ(pass_samples(s, 0), (SampleRange{0, 16})) << to_string(engine);
    EXPECT_THROW(pass_samples(s, 1), InputError) << to_string(engine);
  }
}

TEST(SamplePassRanges, AnOutOfRangePassOrANegativePassSppIsRefused) {
  const PreparedScene scene = glossy_glass_scene();
  RenderSettings s = path_settings(8, 8, 12, 4);  // passes 0, 1, 2
  for (int pass : {-2, 3, 100}) {
    EXPECT_THROW(pass_samples(s, pass), InputError) << pass;
    s.pass = pass;
    TileBuffer out;
    EXPECT_THROW(render_tile(scene, s, Rect{0, 0, 8, 8}, out), InputError) << pass;
    EXPECT_THROW(render_frame(scene, s), InputError) << pass;
  }
  s.pass = 0;
  s.pass_spp = -1;
  TileBuffer out;
  EXPECT_THROW(pass_count(s), InputError);
  EXPECT_THROW(render_tile(scene, s, Rect{0, 0, 8, 8}, out), InputError);
  s.pass = -1;
  EXPECT_THROW(render_frame(scene, s), InputError);
  // A raster or whitted frame has pass 0 only, whatever pass_spp says.
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    RenderSettings r = path_settings(8, 8, 4, 2);
    r.engine = engine;
    r.pass = 1;
    EXPECT_THROW(render_tile(scene, r, Rect{0, 0, 8, 8}, out), InputError) << to_string(engine);
  }
}

// --- Rendering a pass ---

TEST(SamplePassRender, PassesTraceDisjointSamplesWhoseCountsAddUpToSpp) {
  const PreparedScene scene = scene_with_a_bad_lamp();
  RenderSettings s = path_settings(16, 12, 20, 8);  // 8 + 8 + 4
  s.max_depth = 2;
  const TileBuffer whole = test::render_full(scene, s);  // pass -1: all 20 samples in one go
  RenderStats sum;
  std::vector<TileBuffer> passes;
  for (int p = 0; p < pass_count(s); ++p) {
    s.pass = p;
    passes.push_back(test::render_full(scene, s));
    EXPECT_EQ(passes.back().stats().samples, 16u * 12u * static_cast<unsigned>(pass_samples(s, p).count()));
    sum += passes.back().stats();
  }
  // The same samples as the one-go render, each once: the same counts of samples, invalid ones
  // and rays.
  EXPECT_TRUE(same_stats(sum, whole.stats()));
  EXPECT_EQ(sum.samples, 16u * 12u * 20u);
  EXPECT_GT(sum.invalid_samples, 0u);
}

TEST(SamplePassRender, PassesOfEqualSizeTraceDifferentSamplesNotRepeats) {
  const PreparedScene scene = glossy_glass_scene();
  RenderSettings s = path_settings(16, 16, 8, 4);
  s.pass = 0;
  const TileBuffer pass0 = test::render_full(scene, s);
  s.pass = 1;
  const TileBuffer pass1 = test::render_full(scene, s);
  // As many samples, but samples 4..7 of each pixel, not 0..3 again: their noise differs.
  int differ = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) differ += pass0.rgba(x, y) != pass1.rgba(x, y) ? 1 : 0;
  EXPECT_GT(differ, 16 * 16 / 2) << "pass 1 repeated pass 0's samples";
}

// --- Merging ---

TEST(SamplePassMerge, OnePassIsTodaysRenderBitForBit) {
  const PreparedScene scene = glossy_glass_scene();
  const RenderSettings today = path_settings(32, 32, 8, 0);
  const TileBuffer reference = render_frame(scene, today);
  for (int pass_spp : {8, 9, 64}) {  // pass_spp >= spp: one pass
    RenderSettings s = today;
    s.pass_spp = pass_spp;
    const TileBuffer frame = render_frame(scene, s);
    EXPECT_EQ(test::differing_pixels(reference, frame), 0) << pass_spp;
    EXPECT_TRUE(same_stats(reference.stats(), frame.stats()));
    // What a farm merges from pass 0's tiles is the same frame.
    PassAccumulator merged(Rect{0, 0, 32, 32}, s.aovs);
    for (const TileBuffer& tile : render_pass_tiles(scene, s, 0, 16, false)) merged.add(tile, pass_samples(s, 0));
    const TileBuffer farm = merged.resolve();
    EXPECT_EQ(test::differing_pixels(reference, farm), 0) << pass_spp;
    EXPECT_TRUE(same_stats(reference.stats(), farm.stats()));
  }
}

TEST(SamplePassMerge, MergedFrameIsTheSameBitsWhateverTilesThreadsOrderAndRetries) {
  const PreparedScene scene = glossy_glass_scene();
  RenderSettings s = path_settings(32, 32, 12, 4);  // passes 0, 1, 2
  s.threads = 1;
  s.tile_size = 32;
  const TileBuffer reference = render_frame(scene, s);  // in process: every pass, merged
  for (int threads : {2, 3}) {
    for (int tile : {5, 16}) {
      s.threads = threads;
      s.tile_size = tile;
      const TileBuffer frame = render_frame(scene, s);
      EXPECT_EQ(test::differing_pixels(reference, frame), 0) << threads << " threads, tile " << tile;
      EXPECT_TRUE(same_stats(reference.stats(), frame.stats()));
    }
  }

  // A farm: pass 2 rendered first, pass 0 last; each pass in its own tile split and tile order;
  // pass 1 rendered twice (a retried unit), and a unit of pass 0 twice too.
  std::vector<std::vector<TileBuffer>> units(3);
  units[2] = render_pass_tiles(scene, s, 2, 7, true);
  units[1] = render_pass_tiles(scene, s, 1, 32, false);
  const std::vector<TileBuffer> retry = render_pass_tiles(scene, s, 1, 32, false);
  ASSERT_EQ(test::differing_pixels(units[1][0], retry[0]), 0) << "a retry renders the same bits";
  units[0] = render_pass_tiles(scene, s, 0, 16, true);

  PassAccumulator frame(Rect{0, 0, 32, 32}, s.aovs);
  // The scheduler folds a tile's next pass as soon as its pixels have the passes before it, so
  // the passes of different tiles interleave: pass 0 of some tiles, pass 1 over them all, ...
  frame.add(units[0][0], pass_samples(s, 0));
  frame.add(units[0][1], pass_samples(s, 0));
  EXPECT_THROW(frame.add(units[0][1], pass_samples(s, 0)), std::invalid_argument)
      << "a unit folded twice (its retry) is refused";
  EXPECT_THROW(frame.add(units[1][0], pass_samples(s, 1)), std::invalid_argument)
      << "pass 1 cannot fold over pixels that lack pass 0";
  for (std::size_t i = 2; i < units[0].size(); ++i) frame.add(units[0][i], pass_samples(s, 0));
  frame.add(units[1][0], pass_samples(s, 1));
  for (const TileBuffer& unit : units[2]) frame.add(unit, pass_samples(s, 2));

  const TileBuffer farm = frame.resolve();
  EXPECT_EQ(test::differing_pixels(reference, farm), 0);
  EXPECT_TRUE(same_stats(reference.stats(), farm.stats()));
  EXPECT_EQ(frame.samples(0, 0), 12);
  EXPECT_EQ(frame.samples(31, 31), 12);
}

// Pass buffers made from known sample values: the mean and the variance of the mean (the
// unbiased sample variance over n) that the path tracer writes, in float.
struct SyntheticPixel {
  std::vector<std::vector<glm::dvec4>> passes;  // per pass, its samples' RGB and coverage
};

TileBuffer synthetic_pass(const Rect& rect, const std::vector<SyntheticPixel>& pixels, std::size_t pass) {
  AovSet aovs;
  aovs.variance = aovs.depth = true;
  TileBuffer out(rect, aovs);
  std::size_t i = 0;
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x, ++i) {
      const std::vector<glm::dvec4>& v = pixels[i].passes[pass];
      const double n = static_cast<double>(v.size());
      glm::dvec4 mean(0.0);
      for (const glm::dvec4& s : v) mean += s;
      mean /= n;
      glm::dvec3 m2(0.0);
      for (const glm::dvec4& s : v) m2 += (glm::dvec3(s) - glm::dvec3(mean)) * (glm::dvec3(s) - glm::dvec3(mean));
      out.rgba(x, y) = glm::vec4(mean);
      out.variance(x, y) = v.size() < 2 ? glm::vec3(0.0f) : glm::vec3(m2 / (n * (n - 1.0)));
      out.depth(x, y) = static_cast<float>(pass + 1);  // which pass a first-sample AOV came from
    }
  }
  return out;
}

TEST(SamplePassMerge, VarianceCombinationEqualsTheDirectVarianceOfAllSamples) {
  // Passes of 5, 1 and 7 samples (the 1 has no variance of its own), values spread over scales.
  const std::vector<int> sizes = {5, 1, 7};
  const Rect rect{10, 20, 14, 23};  // 4 x 3 pixels, not at the origin
  std::vector<SyntheticPixel> pixels(12);
  std::uint64_t state = 12345;
  const auto uniform = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0);
  };
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const double scale = std::pow(10.0, static_cast<double>(i % 4) - 1.0);  // 0.1 .. 100
    for (int n : sizes) {
      std::vector<glm::dvec4> v;
      for (int k = 0; k < n; ++k)
        v.push_back({scale * uniform(), scale * (1.0 + uniform()), 5.0 * uniform() * uniform(), uniform() < 0.5 ? 1.0 : 0.0});
      pixels[i].passes.push_back(v);
    }
  }
  AovSet aovs;
  aovs.depth = aovs.variance = true;
  PassAccumulator merged(rect, aovs);
  // Pass 1 folded as two tiles, pass 2 as a tile bigger than the rect.
  merged.add(synthetic_pass(rect, pixels, 0), {0, 5});
  const TileBuffer pass1 = synthetic_pass(rect, pixels, 1);
  TileBuffer left(Rect{10, 20, 12, 23}, pass1.aovs()), right(Rect{12, 20, 14, 23}, pass1.aovs());
  left.paste(pass1);
  right.paste(pass1);
  merged.add(right, {5, 6});
  merged.add(left, {5, 6});
  TileBuffer pass2 = synthetic_pass(rect, pixels, 2);
  TileBuffer big(Rect{0, 0, 30, 30}, pass2.aovs());
  big.paste(pass2);
  merged.add(big, {6, 13});
  const TileBuffer image = merged.resolve();

  std::size_t i = 0;
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x, ++i) {
      std::vector<glm::dvec4> all;
      for (const auto& v : pixels[i].passes) all.insert(all.end(), v.begin(), v.end());
      const double n = static_cast<double>(all.size());
      glm::dvec4 mean(0.0);
      for (const glm::dvec4& s : all) mean += s;
      mean /= n;
      glm::dvec3 m2(0.0);
      for (const glm::dvec4& s : all) m2 += (glm::dvec3(s) - glm::dvec3(mean)) * (glm::dvec3(s) - glm::dvec3(mean));
      const glm::dvec3 variance = m2 / (n * (n - 1.0));
      for (int c = 0; c < 4; ++c) {
        EXPECT_NEAR(image.rgba(x, y)[c], mean[c], 1e-6 * std::max(1.0, std::fabs(mean[c]))) << x << "," << y << " c" << c;
      }
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(image.variance(x, y)[c], variance[c], 2e-6 * variance[c]) << x << "," << y << " c" << c;
      }
      EXPECT_EQ(image.depth(x, y), 1.0f) << "first-sample AOVs come from pass 0";
      EXPECT_EQ(merged.samples(x, y), 13);
    }
  }
}

TEST(SamplePassMerge, ProgressiveStateAfterPassKIsTheMergedRenderOfItsSamples) {
  const PreparedScene scene = glossy_glass_scene();
  const RenderSettings s = path_settings(24, 24, 16, 4);  // passes 0..3
  PassAccumulator progressive(Rect{0, 0, 24, 24}, s.aovs);
  for (int k = 0; k < pass_count(s); ++k) {
    for (const TileBuffer& tile : render_pass_tiles(scene, s, k, 8, false)) progressive.add(tile, pass_samples(s, k));
    RenderSettings so_far = s;
    so_far.spp = (k + 1) * s.pass_spp;  // passes 0..k of it are s's passes 0..k
    const TileBuffer expected = render_frame(scene, so_far);
    const TileBuffer preview = progressive.resolve();
    EXPECT_EQ(test::differing_pixels(expected, preview), 0) << "after pass " << k;
    EXPECT_TRUE(same_stats(expected.stats(), preview.stats())) << "after pass " << k;
  }
}

TEST(SamplePassMerge, FourPassesOfSixteenEstimateWhatOnePassOfSixtyFourDoes) {
  // The same 64 global samples either way: the merged mean and variance differ from the one-pass
  // render only by rounding, the first-sample AOVs and the stats not at all.
  const PreparedScene scene = glossy_glass_scene();
  const TileBuffer one = render_frame(scene, path_settings(32, 32, 64, 0));
  const TileBuffer four = render_frame(scene, path_settings(32, 32, 64, 16));
  EXPECT_TRUE(same_stats(one.stats(), four.stats()));
  int noisy = 0;
  double variance_one = 0.0, variance_four = 0.0;
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < 4; ++c) {
        const double a = one.rgba(x, y)[c], b = four.rgba(x, y)[c];
        ASSERT_NEAR(a, b, 1e-5 * std::max(1.0, std::fabs(a))) << x << "," << y << " c" << c;
      }
      for (int c = 0; c < 3; ++c) {
        const double a = one.variance(x, y)[c], b = four.variance(x, y)[c];
        const double mean = one.rgba(x, y)[c];
        ASSERT_NEAR(a, b, 1e-4 * a + 1e-6 * mean * mean) << x << "," << y << " c" << c;
        variance_one += a;
        variance_four += b;
      }
      noisy += one.variance(x, y).x > 0.0f ? 1 : 0;
      const float da = one.depth(x, y), db = four.depth(x, y);
      ASSERT_EQ(std::memcmp(&da, &db, sizeof da), 0) << x << "," << y;
      ASSERT_EQ(one.normal(x, y), four.normal(x, y)) << x << "," << y;
      ASSERT_EQ(one.albedo(x, y), four.albedo(x, y)) << x << "," << y;
    }
  }
  EXPECT_GT(noisy, 32 * 32 / 2) << "the variance compared is not all zeros";
  EXPECT_NEAR(variance_four, variance_one, 1e-5 * variance_one);
}

TEST(SamplePassMerge, RefusesAPassOutOfOrderTwiceOrWithoutTheMergedAovs) {
  AovSet aovs;
  aovs.variance = true;
  const Rect rect{0, 0, 4, 4};
  TileBuffer pass(rect, aovs);
  pass.rgba(1, 1) = glm::vec4(2.0f);
  PassAccumulator merged(rect, aovs);
  EXPECT_THROW(merged.add(pass, {4, 8}), std::invalid_argument) << "pass 1 before pass 0";
  EXPECT_THROW(merged.add(pass, {0, 0}), std::invalid_argument) << "an empty range";
  EXPECT_THROW(merged.add(TileBuffer(Rect{8, 8, 12, 12}, aovs), {0, 4}), std::invalid_argument) << "no overlap";
  EXPECT_THROW(merged.add(TileBuffer(rect, AovSet{}), {0, 4}), std::invalid_argument) << "no variance";
  EXPECT_EQ(merged.samples(1, 1), 0) << "a refused pass changes nothing";
  merged.add(pass, {0, 4});
  // Half the rect already holds pass 1: the whole pass 1 is refused, and nothing of it folded.
  merged.add(TileBuffer(Rect{0, 0, 4, 2}, aovs), {4, 8});
  EXPECT_THROW(merged.add(pass, {4, 8}), std::invalid_argument);
  EXPECT_EQ(merged.samples(1, 3), 4);
  EXPECT_EQ(merged.resolve().rgba(1, 3), glm::vec4(0.0f));
}

// --- Raster and whitted ---

TEST(SamplePassRasterAndWhitted, PassSppChangesNothingAndPassZeroIsTheWholeFrame) {
  const PreparedScene scene = glossy_glass_scene();
  for (EngineKind engine : {EngineKind::Raster, EngineKind::Whitted}) {
    RenderSettings s = path_settings(32, 32, 4, 0);
    s.engine = engine;
    s.max_depth = 5;
    const TileBuffer today = render_frame(scene, s);
    s.pass_spp = 1;
    ASSERT_EQ(pass_count(s), 1);
    const TileBuffer with_passes = render_frame(scene, s);
    EXPECT_EQ(test::differing_pixels(today, with_passes), 0) << to_string(engine);
    s.pass = 0;
    const TileBuffer pass0 = render_frame(scene, s);
    EXPECT_EQ(test::differing_pixels(today, pass0), 0) << to_string(engine);
    // The farm's merge of the one pass is the identity here too.
    PassAccumulator merged(Rect{0, 0, 32, 32}, s.aovs);
    merged.add(pass0, pass_samples(s, 0));
    EXPECT_EQ(test::differing_pixels(today, merged.resolve()), 0) << to_string(engine);
    EXPECT_TRUE(same_stats(today.stats(), merged.resolve().stats())) << to_string(engine);
  }
}

}  // namespace
}  // namespace farm
