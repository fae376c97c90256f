// The SSIM metric against scikit-image's structural_similarity with the same window (Gaussian,
// sigma 1.5, Wang et al.'s constants), on luminance and on each channel, over pairs from barely
// to badly different. scikit-image runs from the test venv that deploy/install-deps.sh makes.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/compare/compare.h"
#include "tests/support/image_pairs.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

TEST(SsimCrossCheck, MeanSsimIsScikitImagesWithinOneThousandth) {
  ASSERT_TRUE(std::filesystem::exists(FARM_TEST_PYTHON))
      << FARM_TEST_PYTHON << " is missing: run deploy/install-deps.sh, which makes the test venv";
  using V = test::Variant;
  const std::vector<V> variants = {
      {.name = "noise 0.01", .noise = 0.01},      {.name = "noise 0.05", .noise = 0.05},
      {.name = "noise 0.2", .noise = 0.2},        {.name = "shift 1", .shift_x = 1},
      {.name = "gain 1.1", .gain = 1.1},          {.name = "offset 0.05", .offset = 0.05},
      {.name = "40 hot pixels", .hot_pixels = 40}, {.name = "shift 3 + noise", .noise = 0.02, .shift_x = 3},
  };
  test::TempDir dir;
  const Image reference = test::synthetic_reference(120, 90);
  write_png_image(reference, dir / "ref.png");
  std::string files;
  for (std::size_t i = 0; i < variants.size(); ++i) {
    write_png_image(test::make_variant(reference, variants[i]), dir / fmt::format("new{}.png", i));
    files += fmt::format(" {} {}", test::shell_quote((dir / "ref.png").string()),
                         test::shell_quote((dir / fmt::format("new{}.png", i)).string()));
  }
  for (const SsimChannels mode : {SsimChannels::luminance, SsimChannels::each}) {
    const test::CommandResult theirs = test::run_command(
        fmt::format("{} {} {}{} 2>&1", test::shell_quote(FARM_TEST_PYTHON),
                    test::shell_quote(std::string(FARM_SOURCE_DIR) + "/tests/python/ssim_values.py"), to_string(mode), files));
    ASSERT_EQ(theirs.exit_code, 0) << theirs.output;
    const nlohmann::json values = nlohmann::json::parse(theirs.output);
    ASSERT_EQ(values.size(), variants.size()) << theirs.output;
    CompareSettings settings;
    settings.metric = Metric::ssim;
    settings.ssim_channels = mode;
    const Image ref = read_image(dir / "ref.png");
    for (std::size_t i = 0; i < variants.size(); ++i) {
      const double ours =
          compare_images(ref, read_image(dir / fmt::format("new{}.png", i)), settings).figure("ssim");
      const double skimage = values[i].get<double>();
      std::printf("%-9s %-18s farm %.6f  scikit-image %.6f  diff %.2e\n", std::string(to_string(mode)).c_str(),
                  variants[i].name.c_str(), ours, skimage, ours - skimage);
      EXPECT_NEAR(ours, skimage, 1e-3) << variants[i].name;
    }
  }
}

}  // namespace
}  // namespace farm
