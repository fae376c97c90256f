// The comparison metrics of renderer/compare on images whose answer is known by construction.
#include "renderer/compare/compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <random>

#include "renderer/compare/compare_json.h"
#include "renderer/compare/metrics.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/rgb8_image.h"
#include "renderer/util/input_error.h"
#include "tests/support/image_pairs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

CompareSettings with_metric(Metric metric) {
  CompareSettings s;
  s.metric = metric;
  return s;
}

TEST(CompareExact, IdenticalBitsPassAndAnyOtherBitsFailNamingTheFirstPixel) {
  const Image a = test::synthetic_reference(32, 24);
  EXPECT_EQ(compare_images(a, a, with_metric(Metric::exact)).verdict, Verdict::pass);
  Image b = a;
  b.at(5, 7, 1) = std::nextafter(b.at(5, 7, 1), 2.0f);  // one ulp
  const CompareResult r = compare_images(a, b, with_metric(Metric::exact));
  EXPECT_EQ(r.verdict, Verdict::fail);
  EXPECT_EQ(r.figure("differing_pixels"), 1.0);
  EXPECT_NE(r.summary.find("(5, 7) G"), std::string::npos) << r.summary;
}

TEST(CompareExact, NanPayloadsAndSignedZerosCount) {
  Image a = make_image(2, 1, {"R"}), b = a;
  a.at(0, 0, 0) = 0.0f;
  b.at(0, 0, 0) = -0.0f;
  const std::uint32_t quiet = 0x7fc00000u, payload = 0x7fc00001u;
  std::memcpy(&a.at(1, 0, 0), &quiet, 4);
  std::memcpy(&b.at(1, 0, 0), &payload, 4);
  EXPECT_EQ(compare_images(a, b, with_metric(Metric::exact)).figure("differing_pixels"), 2.0);
  Image c = a;
  EXPECT_EQ(compare_images(a, c, with_metric(Metric::exact)).verdict, Verdict::pass);  // NaN == NaN bitwise
}

TEST(CompareExact, ChannelsAreMatchedByNameNotOrder) {
  Image a = make_image(1, 1, {"R", "G"}), b = make_image(1, 1, {"G", "R"});
  a.at(0, 0, 0) = 1.0f, a.at(0, 0, 1) = 2.0f;
  b.at(0, 0, 0) = 2.0f, b.at(0, 0, 1) = 1.0f;
  EXPECT_EQ(compare_images(a, b, with_metric(Metric::exact)).verdict, Verdict::pass);
}

TEST(CompareMismatch, SizesOrChannelsThatDifferFailWithTheReasonForEveryMetric) {
  const Image a = test::synthetic_reference(16, 16), b = test::synthetic_reference(16, 15);
  Image grey = make_image(16, 16, {"Y"});
  for (Metric m : kAllMetrics) {
    const CompareResult size = compare_images(a, b, with_metric(m));
    EXPECT_EQ(size.verdict, Verdict::fail) << to_string(m);
    EXPECT_NE(size.summary.find("sizes differ: reference 16x16, new 16x15"), std::string::npos) << size.summary;
    EXPECT_EQ(compare_images(a, grey, with_metric(m)).verdict, Verdict::fail) << to_string(m);
  }
  EXPECT_NE(compare_images(a, grey, with_metric(Metric::threshold)).summary.find("channels differ"), std::string::npos);
  const Image empty;
  EXPECT_EQ(compare_images(empty, empty, with_metric(Metric::threshold)).verdict, Verdict::fail);
}

TEST(CompareThreshold, CountsFailingPixelsAndTheVerdictFollowsFailPercent) {
  const Image a = make_image(10, 10, {"R", "G", "B"});
  Image b = a;
  for (int i = 0; i < 3; ++i) b.at(i, 0, 2) = 0.5f;  // 3 of 100 pixels off by 0.5 in blue
  b.at(9, 9, 0) = 0.01f;                              // one off by 0.01: under fail, over warn
  CompareSettings s = with_metric(Metric::threshold);
  s.fail = 0.1;
  s.warn = 0.001;
  s.fail_percent = 2.0;
  s.warn_percent = 10.0;
  CompareResult r = compare_images(a, b, s);
  EXPECT_EQ(r.figure("failing_pixels"), 3.0);
  EXPECT_EQ(r.figure("warning_pixels"), 4.0);
  EXPECT_EQ(r.verdict, Verdict::fail);  // 3% > 2%
  EXPECT_FLOAT_EQ(static_cast<float>(r.figure("max_error")), 0.5f);
  EXPECT_EQ(r.figure("max_x"), 0.0);
  s.fail_percent = 3.0;  // exactly 3% is allowed (idiff: more than)
  r = compare_images(a, b, s);
  EXPECT_EQ(r.verdict, Verdict::pass);
  s.warn_percent = 3.0;  // 4 warning pixels > 3%
  EXPECT_EQ(compare_images(a, b, s).verdict, Verdict::warn);
  s.hard_fail = 0.4;  // any error above it fails whatever the percentage
  EXPECT_EQ(compare_images(a, b, s).verdict, Verdict::fail);
  // Mean error over all 300 values, and PSNR with idiff's peak of 1.
  EXPECT_NEAR(r.figure("mean_error"), (3 * 0.5 + 0.01) / 300.0, 1e-9);
  EXPECT_NEAR(r.figure("psnr_db"), 20.0 * std::log10(1.0 / std::sqrt((3 * 0.25 + 0.0001) / 300.0)), 1e-6);
}

TEST(CompareThreshold, TheWouldPassThresholdPassesAndAnythingBelowItFails) {
  const Image a = test::synthetic_reference(40, 30);
  const Image b = test::make_variant(a, {.name = "noise", .noise = 0.02});
  CompareSettings s = with_metric(Metric::threshold);
  s.fail = 0.01;
  s.fail_percent = 5.0;
  s.warn = 1.0;
  const CompareResult r = compare_images(a, b, s);
  ASSERT_EQ(r.verdict, Verdict::fail);
  ASSERT_EQ(r.would_pass_key, "fail");
  s.fail = r.would_pass_value;
  EXPECT_EQ(compare_images(a, b, s).verdict, Verdict::pass);
  s.fail = std::nextafter(static_cast<float>(r.would_pass_value), 0.0f);
  EXPECT_EQ(compare_images(a, b, s).verdict, Verdict::fail);
}

TEST(CompareThreshold, RelativeThresholdSparesLargeValuesWithSmallRelativeErrors) {
  Image a = make_image(2, 1, {"R"}), b = a;
  a.at(0, 0, 0) = 100.0f, b.at(0, 0, 0) = 100.5f;  // 0.5% relative
  a.at(1, 0, 0) = 0.1f, b.at(1, 0, 0) = 0.3f;      // 100% relative
  CompareSettings s = with_metric(Metric::threshold);
  s.fail = 0.1;
  s.warn = 0.1;
  EXPECT_EQ(compare_images(a, b, s).figure("failing_pixels"), 2.0);
  s.fail_relative = 0.01;
  EXPECT_EQ(compare_images(a, b, s).figure("failing_pixels"), 1.0);
}

TEST(CompareThreshold, ANanAgainstANumberFailsItsPixelAndNanAgainstNanMatches) {
  Image a = make_image(2, 1, {"R"}), b = a;
  a.at(0, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  a.at(1, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  b.at(1, 0, 0) = std::numeric_limits<float>::quiet_NaN();
  const CompareResult r = compare_images(a, b, with_metric(Metric::threshold));
  EXPECT_EQ(r.figure("failing_pixels"), 1.0);
  EXPECT_EQ(r.figure("nonfinite_mismatches"), 1.0);
  EXPECT_EQ(r.verdict, Verdict::fail);
}

TEST(ComparePsnr, MatchesTheFormulaAndTheVerdictFollowsMinPsnr) {
  const Image a = make_image(8, 8, {"R", "G", "B"});
  const Image b = test::make_variant(a, {.name = "offset", .offset = 0.01});
  CompareSettings s = with_metric(Metric::psnr);
  s.min_psnr = 39.0;
  const CompareResult r = compare_images(a, b, s);
  EXPECT_NEAR(r.figure("psnr_db"), 40.0, 1e-4);  // 20 log10(1 / 0.01)
  EXPECT_EQ(r.verdict, Verdict::pass);
  s.min_psnr = 41.0;
  EXPECT_EQ(compare_images(a, b, s).verdict, Verdict::fail);
  EXPECT_EQ(compare_images(a, a, s).figure("psnr_db"), std::numeric_limits<double>::infinity());
}

TEST(CompareSsim, IsOneForIdenticalImagesAndFallsWithNoise) {
  const Image a = test::synthetic_reference(64, 48);
  CompareSettings s = with_metric(Metric::ssim);
  EXPECT_NEAR(compare_images(a, a, s).figure("ssim"), 1.0, 1e-12);
  double previous = 1.0;
  for (double sigma : {0.01, 0.03, 0.1}) {
    const double ssim = compare_images(a, test::make_variant(a, {.name = "noise", .noise = sigma}), s).figure("ssim");
    EXPECT_LT(ssim, previous) << sigma;
    previous = ssim;
  }
  const Image tiny = test::synthetic_reference(10, 40);
  EXPECT_EQ(compare_images(tiny, tiny, s).verdict, Verdict::fail);  // no 11x11 window fits
}

// Gaussian "renders" of a constant scene: per pixel, a mean of `spp` samples of N(mu, sigma^2),
// with its estimated variance, as the path tracer's variance AOV holds it.
Image noisy_render(int size, double mu, double sigma, int spp, std::uint32_t seed) {
  Image image = make_image(size, size, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  std::mt19937 rng(seed);
  std::normal_distribution<double> sample(mu, sigma);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0.0, sum_squares = 0.0;
        for (int i = 0; i < spp; ++i) {
          const double v = sample(rng);
          sum += v, sum_squares += v * v;
        }
        const double mean = sum / spp;
        image.at(x, y, c) = static_cast<float>(mean);
        image.at(x, y, 3 + c) = static_cast<float>((sum_squares - spp * mean * mean) / (spp - 1) / spp);
      }
  return image;
}

TEST(CompareZtest, SameDistributionPassesABiasOfTwoPercentFailsThroughTheMeanTest) {
  CompareSettings s = with_metric(Metric::ztest);
  const Image a = noisy_render(64, 0.5, 0.3, 16, 1), b = noisy_render(64, 0.5, 0.3, 16, 2);
  const CompareResult same = compare_images(a, b, s);
  EXPECT_EQ(same.verdict, Verdict::pass) << same.summary;
  const Image darker = noisy_render(64, 0.49, 0.3, 16, 3);  // 2% darker: no single pixel can tell
  const CompareResult biased = compare_images(a, darker, s);
  EXPECT_EQ(biased.verdict, Verdict::fail) << biased.summary;
  EXPECT_GE(biased.figure("pass_percent"), 99.75) << "the pixels alone pass; the mean test must catch it";
  EXPECT_GT(std::abs(biased.figure("mean_z")), 5.0);
}

TEST(CompareZtest, WithoutVarianceChannelsItFailsSayingHowToRender) {
  const Image a = test::synthetic_reference(16, 16);
  const CompareResult r = compare_images(a, a, with_metric(Metric::ztest));
  EXPECT_EQ(r.verdict, Verdict::fail);
  EXPECT_NE(r.summary.find("\"aovs\": [\"variance\"]"), std::string::npos) << r.summary;
}

TEST(CompareZtest, DeterministicPixelsThatDifferFail) {
  Image a = make_image(20, 20, {"R", "G", "B", "variance.R", "variance.G", "variance.B"});
  Image b = a;
  for (int y = 0; y < 20; ++y) b.at(3, y, 0) = 0.2f;  // a column moved: 5% of pixels, zero variance
  const CompareResult r = compare_images(a, b, with_metric(Metric::ztest));
  EXPECT_EQ(r.verdict, Verdict::fail);
  EXPECT_NEAR(r.figure("pass_percent"), 100.0 * (1200 - 20) / 1200.0, 1e-9);
}

TEST(CompareDifference, IsTheAbsoluteDifferenceTimesSixteen) {
  Image a = make_image(2, 1, {"R", "G", "B"}), b = a;
  b.at(1, 0, 1) = 0.01f;
  const CompareResult r = compare_images(a, b, with_metric(Metric::threshold));
  ASSERT_EQ(r.difference.width, 2);
  EXPECT_FLOAT_EQ(r.difference.at(1, 0, 1), 0.16f);
  EXPECT_EQ(r.difference.at(0, 0, 0), 0.0f);
}

TEST(CompareJson, CarriesTheVerdictFiguresAndInfinityAsAString) {
  const Image a = test::synthetic_reference(16, 16);
  const auto json = to_json(compare_images(a, a, with_metric(Metric::threshold)));
  EXPECT_EQ(json["verdict"], "PASS");
  EXPECT_EQ(json["metric"], "threshold");
  EXPECT_EQ(json["figures"]["psnr_db"], "inf");
  EXPECT_EQ(json["would_pass"]["key"], "fail");
}

TEST(ReadImage, PngValuesAndExrChannelsReadAsStored) {
  test::TempDir dir;
  Image a = test::synthetic_reference(7, 5);
  write_png_image(a, dir / "a.png");
  const Image png = read_image(dir / "a.png");
  EXPECT_TRUE(png.display_referred);
  ASSERT_EQ(png.channels, (std::vector<std::string>{"R", "G", "B"}));
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(png.at(3, 2, c), std::round(a.at(3, 2, c) * 255.0f) / 255.0f);

  Image layered = make_image(3, 2, {"variance.R", "Z", "B", "G", "R"});
  layered.at(2, 1, 1) = 7.25f;
  write_exr_image(layered, dir / "l.exr");
  const Image exr = read_image(dir / "l.exr");
  EXPECT_FALSE(exr.display_referred);
  EXPECT_EQ(exr.channels, (std::vector<std::string>{"R", "G", "B", "Z", "variance.R"}));
  EXPECT_EQ(exr.at(2, 1, exr.channel("Z")), 7.25f);
}

TEST(ReadImage, MissingTruncatedAndNonImageFilesAreInputErrorsNamingTheFile) {
  test::TempDir dir;
  const auto expect_input_error = [](const std::filesystem::path& file, const std::string& words) {
    try {
      read_image(file);
      ADD_FAILURE() << file << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  expect_input_error(dir / "none.png", "no such file");
  expect_input_error(dir.write("text.png", "hello, not a picture"), "not an EXR, PNG or JPEG");
  write_png_image(test::synthetic_reference(64, 64), dir / "whole.png");
  std::ifstream in(dir / "whole.png", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  expect_input_error(dir.write("cut.png", bytes.substr(0, bytes.size() / 2)), "cannot read PNG");
  expect_input_error(dir.write("cut.exr", std::string("\x76\x2f\x31\x01", 4) + "junk"), "cannot read EXR");
  expect_input_error(dir.write("cut.jpg", std::string("\xff\xd8\xff\xe0", 4) + "junk"), "cannot read JPEG");
}

}  // namespace
}  // namespace farm
