// The threshold metric against OpenImageIO's idiff (openimageio-tools), which a user can run on
// the same pair with the same flags: on generated pairs that span PASS, WARN and FAIL (noise,
// shifts, gains, offsets, hot pixels; 8-bit PNG and float EXR, values above 1 too), the verdict
// and the counts of failing and warning pixels must be idiff's.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstdio>
#include <regex>
#include <string>
#include <vector>

#include "renderer/compare/compare.h"
#include "tests/support/image_pairs.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

struct Case {
  test::Variant variant;
  bool exr = false;  // float EXR (values not clamped) rather than 8-bit PNG
  CompareSettings settings;
};

CompareSettings thresholds(double fail, double fail_percent, double warn = 1e-6, double warn_percent = 0.0) {
  CompareSettings s;
  s.fail = fail, s.fail_percent = fail_percent, s.warn = warn, s.warn_percent = warn_percent;
  return s;
}

CompareSettings with(CompareSettings s, double CompareSettings::*field, double value) {
  s.*field = value;
  return s;
}

std::string idiff_flags(const CompareSettings& s) {
  std::string flags = fmt::format("-fail {:.9g} -failpercent {:.9g} -warn {:.9g} -warnpercent {:.9g}", s.fail,
                                  s.fail_percent, s.warn, s.warn_percent);
  if (s.fail_relative > 0) flags += fmt::format(" -failrelative {:.9g}", s.fail_relative);
  if (s.warn_relative > 0) flags += fmt::format(" -warnrelative {:.9g}", s.warn_relative);
  if (std::isfinite(s.hard_fail)) flags += fmt::format(" -hardfail {:.9g}", s.hard_fail);
  if (std::isfinite(s.hard_warn)) flags += fmt::format(" -hardwarn {:.9g}", s.hard_warn);
  return flags;
}

// idiff's exit code: 0 PASS, 1 WARNING, 2 FAILURE (3 and up: it could not compare).
std::string idiff_verdict(int code) {
  switch (code) {
    case 0: return "PASS";
    case 1: return "WARN";
    case 2: return "FAIL";
    default: return fmt::format("idiff error {}", code);
  }
}

TEST(IdiffCrossCheck, ThresholdVerdictsAndPixelCountsEqualIdiffsWithTheSameFlags) {
  using V = test::Variant;
  const std::vector<Case> cases = {
      {V{.name = "identical"}, false, thresholds(1e-6, 0)},
      {V{.name = "noise 0.002", .noise = 0.002}, false, thresholds(0.01, 0)},
      {V{.name = "noise 0.01", .noise = 0.01}, false, thresholds(0.02, 1)},
      {V{.name = "noise 0.01 strict", .noise = 0.01}, false, thresholds(0.05, 0)},
      {V{.name = "noise 0.05", .noise = 0.05}, false, thresholds(0.1, 5)},
      {V{.name = "noise 0.01 warn", .noise = 0.01}, false, thresholds(0.03, 1, 0.02, 5)},
      {V{.name = "noise 0.03 warn", .noise = 0.03}, false, thresholds(0.1, 1, 0.05, 2)},
      {V{.name = "shift 1", .shift_x = 1}, false, thresholds(0.05, 1)},
      {V{.name = "shift 1 loose", .shift_x = 1}, false, thresholds(0.05, 20)},
      {V{.name = "shift 2", .shift_x = 2}, false, thresholds(0.3, 2)},
      {V{.name = "gain 1.01", .gain = 1.01}, false, thresholds(0.016, 1)},
      {V{.name = "gain 1.05", .gain = 1.05}, false, thresholds(0.016, 1)},
      {V{.name = "offset 0.003", .offset = 0.003}, false, thresholds(0.01, 0, 0.002, 0)},
      {V{.name = "offset -0.02", .offset = -0.02}, false, thresholds(0.01, 50)},
      {V{.name = "3 hot pixels", .hot_pixels = 3}, false, thresholds(0.1, 1)},
      {V{.name = "3 hot pixels hardfail", .hot_pixels = 3}, false, with(thresholds(0.1, 1), &CompareSettings::hard_fail, 0.5)},
      {V{.name = "3 hot pixels hardwarn", .hot_pixels = 3}, false, with(thresholds(0.1, 1, 0.1, 1), &CompareSettings::hard_warn, 0.5)},
      {V{.name = "20 hot pixels", .hot_pixels = 20}, false, thresholds(0.1, 0.1)},
      {V{.name = "exr noise", .noise = 0.01}, true, thresholds(0.02, 1)},
      {V{.name = "exr gain 3 (HDR)", .gain = 3.0}, true, with(thresholds(0.01, 0), &CompareSettings::fail_relative, 0.1)},
      {V{.name = "exr gain 1.05 rel 6%", .gain = 1.05}, true, with(thresholds(0.01, 0), &CompareSettings::fail_relative, 0.06)},
      {V{.name = "exr gain 1.05 rel 4%", .gain = 1.05}, true, with(thresholds(0.01, 0), &CompareSettings::fail_relative, 0.04)},
      {V{.name = "exr noise warnrelative", .noise = 0.02}, true,
       with(thresholds(0.5, 0, 0.01, 0), &CompareSettings::warn_relative, 0.05)},
  };
  test::TempDir dir;
  const Image reference = test::synthetic_reference(96, 64);
  write_png_image(reference, dir / "ref.png");
  write_exr_image(reference, dir / "ref.exr");
  int passes = 0, warns = 0, fails = 0;
  std::printf("%-26s %-8s %-8s %14s %14s\n", "pair", "farm", "idiff", "failing farm", "idiff");
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    const std::filesystem::path ref = dir / (c.exr ? "ref.exr" : "ref.png");
    const std::filesystem::path file = dir / fmt::format("new{}.{}", i, c.exr ? "exr" : "png");
    const Image variant = test::make_variant(reference, c.variant, !c.exr);
    if (c.exr) {
      write_exr_image(variant, file);
    } else {
      write_png_image(variant, file);
    }
    // Both read the files as stored: ours through read_image, idiff through OpenImageIO.
    CompareSettings settings = c.settings;
    settings.metric = Metric::threshold;
    const CompareResult ours = compare_images(read_image(ref), read_image(file), settings);
    const test::CommandResult idiff =
        test::run_command("idiff -v " + idiff_flags(settings) + " " + test::shell_quote(ref.string()) + " " + test::shell_quote(file.string()));
    // "  N pixels (P%) over T": the warning count, then the failing count.
    std::vector<long> counts;
    static const std::regex over(R"(\n\s*(\d+) pixels \([^)]*\) over )");
    for (auto it = std::sregex_iterator(idiff.output.begin(), idiff.output.end(), over); it != std::sregex_iterator(); ++it)
      counts.push_back(std::stol((*it)[1]));
    const std::string verdict(to_string(ours.verdict));
    std::printf("%-26s %-8s %-8s %14.0f %14ld\n", c.variant.name.c_str(), verdict.c_str(),
                idiff_verdict(idiff.exit_code).c_str(), ours.figure("failing_pixels"), counts.empty() ? -1L : counts.back());
    EXPECT_EQ(verdict, idiff_verdict(idiff.exit_code)) << c.variant.name << "\n" << ours.summary << "\n" << idiff.output;
    if (counts.size() == 2) {
      EXPECT_EQ(ours.figure("warning_pixels"), static_cast<double>(counts[0])) << c.variant.name;
      EXPECT_EQ(ours.figure("failing_pixels"), static_cast<double>(counts[1])) << c.variant.name;
    } else {
      EXPECT_EQ(ours.figure("failing_pixels"), 0.0) << c.variant.name << ": idiff printed no counts\n" << idiff.output;
    }
    passes += ours.verdict == Verdict::pass, warns += ours.verdict == Verdict::warn, fails += ours.verdict == Verdict::fail;
  }
  // The pairs must span the verdicts, or the agreement says little.
  EXPECT_GE(passes, 3);
  EXPECT_GE(warns, 3);
  EXPECT_GE(fails, 5);
}

}  // namespace
}  // namespace farm
