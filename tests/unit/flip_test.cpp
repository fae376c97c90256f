// renderer/compare/flip: behaviour that follows from the metric's definition (the agreement with
// NVIDIA's implementation is tests/image/flip_crosscheck_test.cpp).
#include "renderer/compare/flip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <vector>

#include "renderer/util/thread_pool.h"

namespace farm {
namespace {

Image make(int w, int h, std::vector<std::string> channels, const std::function<float(int, int, int)>& value) {
  Image image;
  image.width = w;
  image.height = h;
  image.channels = std::move(channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (std::size_t c = 0; c < image.channels.size(); ++c) image.values.push_back(value(x, y, static_cast<int>(c)));
  return image;
}

Image rgb(int w, int h, const std::function<float(int, int, int)>& value) { return make(w, h, {"R", "G", "B"}, value); }

// Something with edges, gradients and colour: a checker over a diagonal ramp.
float pattern(int x, int y, int c) {
  const float ramp = static_cast<float>(x + y) / 128.0f;
  return ((x / 8 + y / 8) % 2 ? 0.2f : 0.7f) * (0.5f + 0.5f * ramp) + 0.1f * static_cast<float>(c);
}

float error_at(const FlipResult& r, int x, int y) { return r.error_map.at(x, y, 0); }

TEST(FlipTest, IdenticalImagesHaveNoError) {
  ThreadPool pool(2);
  const Image image = rgb(64, 48, pattern);
  const FlipResult result = flip_ldr(image, image, FlipOptions{}, &pool);
  EXPECT_EQ(result.mean, 0.0);
  ASSERT_EQ(result.error_map.channels, std::vector<std::string>{"FLIP"});
  ASSERT_EQ(result.error_map.width, 64);
  ASSERT_EQ(result.error_map.height, 48);
  EXPECT_TRUE(std::all_of(result.error_map.values.begin(), result.error_map.values.end(), [](float v) { return v == 0.0f; }));
}

TEST(FlipTest, ErrorGrowsWithTheColourDifference) {
  ThreadPool pool(2);
  const Image grey = rgb(32, 32, [](int, int, int) { return 0.5f; });
  double previous = 0.0;
  for (float shift : {0.01f, 0.03f, 0.08f, 0.2f, 0.45f}) {
    const Image redder = rgb(32, 32, [&](int, int, int c) { return c == 0 ? 0.5f + shift : 0.5f; });
    const FlipResult result = flip_ldr(grey, redder, FlipOptions{}, &pool);
    EXPECT_GT(result.mean, previous) << "red + " << shift;
    // A uniform change has no edges: every pixel has the same error, in (0, 1].
    EXPECT_NEAR(error_at(result, 0, 0), result.mean, 1e-5);
    EXPECT_LE(result.mean, 1.0);
    previous = result.mean;
  }
}

TEST(FlipTest, AOnePixelEdgeShiftIsSeenAtTheEdgeOnly) {
  ThreadPool pool(2);
  const auto edge_at = [](int column) {
    return rgb(96, 16, [=](int x, int, int) { return x < column ? 0.1f : 0.9f; });
  };
  const FlipResult result = flip_ldr(edge_at(48), edge_at(49), FlipOptions{}, &pool);
  // Far from the edge (beyond every kernel's reach) nothing differs.
  EXPECT_EQ(error_at(result, 5, 8), 0.0f);
  EXPECT_EQ(error_at(result, 90, 8), 0.0f);
  // At the edge the feature term (edge strength changes there) lifts the error well above what
  // the blurred colour difference alone gives a few pixels away.
  float peak = 0.0f;
  int peak_x = 0;
  for (int x = 0; x < 96; ++x) {
    if (error_at(result, x, 8) > peak) peak = error_at(result, x, 8), peak_x = x;
  }
  EXPECT_GT(peak, 0.6f);
  EXPECT_NEAR(peak_x, 48, 2);
  EXPECT_LT(error_at(result, peak_x - 4, 8), 0.2f * peak);
  EXPECT_LT(error_at(result, peak_x + 4, 8), 0.2f * peak);
}

TEST(FlipTest, ResultDoesNotDependOnTheThreadCount) {
  // Bands of rows are filtered separately with overlaps; the seams must not show.
  const Image reference = rgb(200, 150, pattern);
  const Image test = rgb(200, 150, [](int x, int y, int c) { return pattern(x + (y > 70 ? 1 : 0), y, c); });
  ThreadPool one(1), three(3);
  const FlipResult a = flip_ldr(reference, test, FlipOptions{}, &one);
  const FlipResult b = flip_ldr(reference, test, FlipOptions{}, &three);
  EXPECT_GT(a.mean, 0.0);
  EXPECT_EQ(a.error_map.values, b.error_map.values);
  const FlipResult c = flip_ldr(reference, test, FlipOptions{}, nullptr);  // a pool of its own
  EXPECT_EQ(a.error_map.values, c.error_map.values);
}

TEST(FlipTest, GreyImagesAreReadAsEqualRgb) {
  ThreadPool pool(2);
  const auto grey = [](float offset) {
    return make(40, 40, {"Y"}, [=](int x, int y, int) { return pattern(x, y, 0) + offset; });
  };
  const auto as_rgb = [](float offset) {
    return rgb(40, 40, [=](int x, int y, int) { return pattern(x, y, 0) + offset; });
  };
  const FlipResult from_grey = flip_ldr(grey(0.0f), grey(0.05f), FlipOptions{}, &pool);
  const FlipResult from_rgb = flip_ldr(as_rgb(0.0f), as_rgb(0.05f), FlipOptions{}, &pool);
  EXPECT_GT(from_grey.mean, 0.0);
  EXPECT_EQ(from_grey.mean, from_rgb.mean);
}

TEST(FlipTest, OtherChannelsAreIgnored) {
  ThreadPool pool(2);
  const Image plain = rgb(24, 24, pattern);
  const Image with_alpha_and_depth = make(24, 24, {"A", "B", "G", "R", "Z"}, [](int x, int y, int c) {
    return c == 1 ? pattern(x, y, 2) : c == 2 ? pattern(x, y, 1) : c == 3 ? pattern(x, y, 0) : 7.0f;
  });
  EXPECT_EQ(flip_ldr(plain, with_alpha_and_depth, FlipOptions{}, &pool).mean, 0.0);
}

TEST(FlipTest, BadInputsThrow) {
  ThreadPool pool(1);
  const Image a = rgb(16, 16, pattern), wider = rgb(17, 16, pattern);
  EXPECT_THROW(flip_ldr(a, wider, FlipOptions{}, &pool), std::invalid_argument);
  EXPECT_THROW(flip_hdr(a, wider, FlipOptions{}, &pool), std::invalid_argument);
  try {
    flip_ldr(a, wider, FlipOptions{}, &pool);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("16x16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("17x16"), std::string::npos) << e.what();
  }
  const Image depth_only = make(16, 16, {"Z"}, [](int, int, int) { return 1.0f; });
  EXPECT_THROW(flip_ldr(a, depth_only, FlipOptions{}, &pool), std::invalid_argument);
  const Image red_green = make(16, 16, {"R", "G"}, [](int, int, int) { return 1.0f; });
  EXPECT_THROW(flip_ldr(red_green, a, FlipOptions{}, &pool), std::invalid_argument);
  FlipOptions no_viewer;
  no_viewer.pixels_per_degree = 0.0;
  EXPECT_THROW(flip_ldr(a, a, no_viewer, &pool), std::invalid_argument);
  FlipOptions backwards;
  backwards.automatic_exposures = false;
  backwards.start_exposure = 2.0;
  backwards.stop_exposure = -2.0;
  EXPECT_THROW(flip_hdr(a, a, backwards, &pool), std::invalid_argument);
}

// A linear HDR image: a dim ramp with a few very bright pixels.
Image hdr_scene(float gain = 1.0f) {
  return rgb(48, 48, [=](int x, int y, int c) {
    const float base = 0.05f + 0.02f * static_cast<float>(x) + 0.1f * static_cast<float>(c);
    return gain * ((x % 17 == 3 && y % 13 == 5) ? 80.0f : base);
  });
}

TEST(FlipTest, HdrOfAnImageAgainstItselfIsZero) {
  ThreadPool pool(2);
  const Image scene = hdr_scene();
  const FlipResult result = flip_hdr(scene, scene, FlipOptions{}, &pool);
  EXPECT_EQ(result.mean, 0.0);
  EXPECT_LT(result.start_exposure, result.stop_exposure);
  EXPECT_GE(result.exposure_count, 2);
  EXPECT_EQ(result.exposure_count,
            std::max(2, static_cast<int>(std::ceil(result.stop_exposure - result.start_exposure))));
}

TEST(FlipTest, HdrUsesTheExposuresItIsGiven) {
  ThreadPool pool(2);
  FlipOptions options;
  options.automatic_exposures = false;
  options.start_exposure = -3.0;
  options.stop_exposure = 1.0;
  options.exposure_count = 5;
  const FlipResult result = flip_hdr(hdr_scene(), hdr_scene(1.2f), options, &pool);
  EXPECT_EQ(result.start_exposure, -3.0);
  EXPECT_EQ(result.stop_exposure, 1.0);
  EXPECT_EQ(result.exposure_count, 5);
  EXPECT_GT(result.mean, 0.0);
  // The error of each pixel is its largest over the exposures: more exposures can only add.
  FlipOptions fewer = options;
  fewer.exposure_count = 2;  // -3 and 1, both among the five
  const FlipResult subset = flip_hdr(hdr_scene(), hdr_scene(1.2f), fewer, &pool);
  for (std::size_t p = 0; p < subset.error_map.values.size(); ++p)
    ASSERT_LE(subset.error_map.values[p], result.error_map.values[p]);
}

TEST(FlipTest, HdrOfAMostlyBlackReferenceStillSeesDifferences) {
  // More than half the pixels black: the median luminance is 0, which would give no stop
  // exposure; it is held to FLT_EPSILON, as flip-evaluator 1.7 does.
  ThreadPool pool(2);
  const auto scene = [](float gain) {
    return rgb(32, 32, [=](int x, int, int) { return x < 20 ? 0.0f : gain * 0.5f; });
  };
  const FlipResult result = flip_hdr(scene(1.0f), scene(1.5f), FlipOptions{}, &pool);
  // 2.11887: where the ACES curve reaches 0.85.
  EXPECT_NEAR(result.stop_exposure, std::log2(2.11887 / 1.1920929e-7), 1e-3);
  EXPECT_GT(result.mean, 0.0);
  // An all-black reference: one range at that exposure (flip-evaluator gives up on it).
  const Image black = rgb(8, 8, [](int, int, int) { return 0.0f; });
  const Image grey = rgb(8, 8, [](int, int, int) { return 0.01f; });
  EXPECT_EQ(flip_hdr(black, black, FlipOptions{}, &pool).mean, 0.0);
  const FlipResult lit = flip_hdr(black, grey, FlipOptions{}, &pool);
  EXPECT_EQ(lit.start_exposure, lit.stop_exposure);
  EXPECT_GT(lit.mean, 0.5);
}

TEST(FlipTest, MagmaMapsZeroAndOneToTheTableEnds) {
  Image errors = make(3, 1, {"FLIP"}, [](int x, int, int) { return x * 0.5f; });
  const Image colours = flip_magma(errors);
  ASSERT_EQ(colours.channels, (std::vector<std::string>{"R", "G", "B"}));
  EXPECT_TRUE(colours.display_referred);
  EXPECT_FLOAT_EQ(colours.at(0, 0, 0), 0.001462f);
  EXPECT_FLOAT_EQ(colours.at(0, 0, 1), 0.000466f);
  EXPECT_FLOAT_EQ(colours.at(0, 0, 2), 0.013866f);
  EXPECT_FLOAT_EQ(colours.at(2, 0, 0), 0.987053f);
  EXPECT_FLOAT_EQ(colours.at(2, 0, 1), 0.991438f);
  EXPECT_FLOAT_EQ(colours.at(2, 0, 2), 0.749504f);
  // Half way: entry 128 (0.5 * 255 rounds up), a magenta-red.
  EXPECT_GT(colours.at(1, 0, 0), 0.7f);
  EXPECT_LT(colours.at(1, 0, 1), 0.25f);
  // Out-of-range errors are held to the ends.
  errors.values = {-1.0f, 2.0f, NAN};
  const Image held = flip_magma(errors);
  EXPECT_EQ(held.at(0, 0, 0), colours.at(0, 0, 0));
  EXPECT_EQ(held.at(1, 0, 2), colours.at(2, 0, 2));
  EXPECT_EQ(held.at(2, 0, 1), colours.at(0, 0, 1));
}

}  // namespace
}  // namespace farm
