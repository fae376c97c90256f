// `farm compare REF NEW` as a user runs it: exit 0 for PASS (and WARN), 1 for FAIL, 2 for a file
// that cannot be read or a threshold out of range; --json and --diff.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "renderer/compare/image.h"
#include "tests/support/image_pairs.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

class FarmCompareTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const Image reference = test::synthetic_reference(40, 30);
    write_png_image(reference, dir_ / "ref.png");
    write_png_image(reference, dir_ / "same.png");
    write_png_image(test::make_variant(reference, {.name = "noise", .noise = 0.05}), dir_ / "noisy.png");
  }
  test::CommandResult compare(const std::string& args) {
    return test::run_command(test::farm_command("compare " + args + " 2>&1"));
  }
  std::string file(const char* name) { return test::shell_quote((dir_ / name).string()); }

  test::TempDir dir_;
};

TEST_F(FarmCompareTest, ExitCodesFollowTheVerdictAndBadInputIsTwo) {
  const test::CommandResult same = compare(file("ref.png") + " " + file("same.png"));
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("\nPASS\n"), std::string::npos) << same.output;

  const test::CommandResult noisy = compare(fmt::format("{} {} --fail 0.05 --fail-percent 1 --diff {}", file("ref.png"),
                                                        file("noisy.png"), file("diff.png")));
  EXPECT_EQ(noisy.exit_code, 1) << noisy.output;
  EXPECT_NE(noisy.output.find("would pass with --fail "), std::string::npos) << noisy.output;
  const Image diff = read_image(dir_ / "diff.png");
  EXPECT_EQ(diff.width, 40);

  const test::CommandResult loose = compare(fmt::format("{} {} --metric psnr --min-psnr 20", file("ref.png"), file("noisy.png")));
  EXPECT_EQ(loose.exit_code, 0) << loose.output;

  const test::CommandResult missing = compare(file("ref.png") + " " + file("none.png"));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("none.png: no such file"), std::string::npos) << missing.output;
  const test::CommandResult range = compare(file("ref.png") + " " + file("same.png") + " --fail-percent 200");
  EXPECT_EQ(range.exit_code, 2) << range.output;
}

TEST_F(FarmCompareTest, JsonCarriesTheVerdictFiguresAndTheThresholdThatWouldPass) {
  const test::CommandResult r =
      compare(fmt::format("{} {} --metric ssim --min-ssim 0.99 --json", file("ref.png"), file("noisy.png")));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["verdict"], "FAIL");
  EXPECT_EQ(j["metric"], "ssim");
  EXPECT_LT(j["figures"]["ssim"].get<double>(), 0.99);
  EXPECT_EQ(j["would_pass"]["key"], "min_ssim");
  EXPECT_DOUBLE_EQ(j["would_pass"]["value"].get<double>(), j["figures"]["ssim"].get<double>());
}

}  // namespace
}  // namespace farm
