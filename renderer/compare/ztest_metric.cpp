// ztest: the test Mitsuba 3 applies to Monte Carlo renders, which tells noise from error. Both
// images carry the variance of each pixel's mean estimate (the `variance` AOV). Per pixel and
// channel, z = (a - b) / sqrt(var_a + var_b) has a standard normal distribution when both
// estimate the same value; its two-sided p-value is tested at the Sidak-corrected level
// 1 - (1 - alpha)^(1/N) for N pixel-channels, and at least `min_pass_percent` of them must pass
// (fireflies have heavier tails than a normal). A bias too small for any one pixel (a uniform 2%
// darker image) still moves the image mean by many standard errors, so the mean is tested too.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "renderer/compare/metrics.h"

namespace farm {
namespace {

constexpr std::array<const char*, 3> kColour = {"R", "G", "B"};
constexpr std::array<const char*, 3> kVariance = {"variance.R", "variance.G", "variance.B"};

// A floor under var_a + var_b: a pixel every sample of which has the same value (background,
// a directly seen lamp) has zero variance in both images and the same mean; rounding aside, its
// z is then 0/0. The floor covers float rounding of values that size.
double variance_floor(double a, double b) {
  const double scale = 1e-6 * std::max(std::abs(a), std::abs(b));
  return 1e-30 + scale * scale;
}

double two_sided_p(double z) { return std::erfc(std::abs(z) / std::sqrt(2.0)); }

std::string missing_channels(const Image& image) {
  std::string missing;
  for (const char* name : kVariance)
    if (image.channel(name) < 0) missing += std::string(missing.empty() ? "" : " ") + name;
  for (const char* name : kColour)
    if (image.channel(name) < 0) missing += std::string(missing.empty() ? "" : " ") + name;
  return missing;
}

}  // namespace

CompareResult ztest_metric(const Image& reference, const Image& test, const CompareSettings& s) {
  CompareResult result;
  for (const auto& [image, which] : {std::pair{&reference, "reference"}, std::pair{&test, "new image"}}) {
    if (std::string missing = missing_channels(*image); !missing.empty()) {
      result.verdict = Verdict::fail;
      result.summary = fmt::format("the z-test needs R G B and variance.R/G/B in both images; the {} lacks {} "
                                   "(render the path tracer with \"aovs\": [\"variance\"])",
                                   which, missing);
      return result;
    }
  }
  std::array<int, 3> ra{}, rv{}, ta{}, tv{};
  for (std::size_t c = 0; c < 3; ++c) {
    ra[c] = reference.channel(kColour[c]), rv[c] = reference.channel(kVariance[c]);
    ta[c] = test.channel(kColour[c]), tv[c] = test.channel(kVariance[c]);
  }
  const double n = 3.0 * static_cast<double>(reference.pixel_count());
  // 1 - (1 - alpha)^(1/N), computed without cancellation.
  const double alpha_value = -std::expm1(std::log1p(-s.alpha) / n);

  result.difference = make_image(reference.width, reference.height, {"R", "G", "B"});
  std::size_t failing = 0;
  double sum_difference = 0.0, sum_variance = 0.0, max_z = 0.0;
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      double smallest_p = 1.0;
      bool pixel_fails = false;
      for (std::size_t c = 0; c < 3; ++c) {
        const double a = reference.at(x, y, ra[c]), b = test.at(x, y, ta[c]);
        const double variance = std::max(0.0, static_cast<double>(reference.at(x, y, rv[c]))) +
                                std::max(0.0, static_cast<double>(test.at(x, y, tv[c])));
        double p = 0.0;
        if (std::isfinite(a) && std::isfinite(b) && std::isfinite(variance)) {
          const double z = (a - b) / std::sqrt(variance + variance_floor(a, b));
          max_z = std::max(max_z, std::abs(z));
          p = two_sided_p(z);
          sum_difference += a - b;
          sum_variance += variance;
        }
        smallest_p = std::min(smallest_p, p);
        if (!(p > alpha_value)) ++failing, pixel_fails = true;
      }
      // The p-map: grey rising to white as p approaches the per-value level; red where a value fails.
      const float level = static_cast<float>(std::clamp(std::log10(std::max(smallest_p, 1e-300)) / std::log10(alpha_value), 0.0, 1.0));
      result.difference.at(x, y, 0) = pixel_fails ? 1.0f : level;
      result.difference.at(x, y, 1) = pixel_fails ? 0.0f : level;
      result.difference.at(x, y, 2) = pixel_fails ? 0.0f : level;
    }
  const double pass_percent = 100.0 * (n - static_cast<double>(failing)) / n;
  // The image mean: the difference of means over its standard error (pixels are independent).
  const double mean_difference = sum_difference / n;
  const double standard_error = std::sqrt(sum_variance) / n;
  const double mean_z = mean_difference / std::sqrt(standard_error * standard_error + 1e-30);
  const double mean_p = two_sided_p(mean_z);
  const bool pixels_pass = pass_percent >= s.min_pass_percent;
  const bool mean_passes = mean_p > s.alpha;

  result.verdict = pixels_pass && mean_passes ? Verdict::pass : Verdict::fail;
  result.figures = {{"mean_z", mean_z},
                    {"mean_p", mean_p},
                    {"mean_difference", mean_difference},
                    {"pass_percent", pass_percent},
                    {"failing_values", static_cast<double>(failing)},
                    {"max_abs_z", max_z},
                    {"alpha_per_value", alpha_value}};
  if (!pixels_pass || mean_passes) {
    result.would_pass_key = "min_pass_percent";
    result.would_pass_value = pass_percent;
  } else {
    result.would_pass_key = "alpha";
    result.would_pass_value = mean_p;
  }
  result.summary = fmt::format("mean z {:.2f} (p {:.3g}, needs > {:g}), {:.2f}% of pixel-channels pass (needs {:g}%)",
                               mean_z, mean_p, s.alpha, pass_percent, s.min_pass_percent);
  return result;
}

}  // namespace farm
