// ztest: the test Mitsuba 3 applies to Monte Carlo renders, which tells noise from error. Both
// images carry the variance of each pixel's mean estimate (the `variance` AOV). Per pixel and
// channel, z = (a - b) / sqrt(var_a + var_b) has a standard normal distribution when both
// estimate the same value; its two-sided p-value is tested at the Sidak-corrected level
// 1 - (1 - alpha)^(1/N) for N pixel-channels, and at least `min_pass_percent` of them must pass
// (fireflies have heavier tails than a normal). A bias too small for any one pixel (a uniform 2%
// darker image) still moves the image mean by many standard errors, so each channel's mean is
// tested too. Per channel, not summed over channels: R, G and B of a pixel come from the same
// paths, so their errors are correlated and the variance of a sum over channels is not the sum
// of their variances (that would make z about 1.7 times too large).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "renderer/compare/metrics.h"

namespace farm {
namespace {

constexpr std::array<const char*, 3> kColour = {"R", "G", "B"};
constexpr std::array<const char*, 3> kVariance = {"variance.R", "variance.G", "variance.B"};

// A floor under var_a + var_b. A pixel every sample of which has the same value (background, a
// directly seen lamp) has zero variance in both images and the same mean: z would be 0/0. And
// EXRs hold colour as half floats by default, whose rounding (up to half an ulp, 2^-11 of the
// value, in each image) is an error the variance AOV does not include: the floor is that
// rounding's variance, |v| 2^-10 squared over 12 per image.
double variance_floor(double a, double b) {
  const double ulp = std::ldexp(std::max(std::abs(a), std::abs(b)), -10);
  return 1e-30 + ulp * ulp / 6.0;
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
  std::array<double, 3> sum_difference{}, sum_variance{};
  double max_z = 0.0;
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
          sum_difference[c] += a - b;
          sum_variance[c] += variance;
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
  // Each channel's image mean: the difference of means over its standard error (pixels are
  // independent), at the level Sidak-corrected for the three channels. The channel furthest
  // from agreement is reported.
  const double pixels = static_cast<double>(reference.pixel_count());
  const double alpha_channel = -std::expm1(std::log1p(-s.alpha) / 3.0);
  double mean_z = 0.0, mean_difference = 0.0;
  for (std::size_t c = 0; c < 3; ++c) {
    const double difference = sum_difference[c] / pixels, standard_error = std::sqrt(sum_variance[c]) / pixels;
    const double z = difference / std::sqrt(standard_error * standard_error + 1e-30);
    if (std::abs(z) >= std::abs(mean_z)) mean_z = z, mean_difference = difference;
  }
  const double mean_p = two_sided_p(mean_z);
  const bool pixels_pass = pass_percent >= s.min_pass_percent;
  const bool mean_passes = mean_p > alpha_channel;

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
    result.would_pass_value = -std::expm1(3.0 * std::log1p(-mean_p));  // the alpha whose per-channel level is mean_p
  }
  result.summary = fmt::format("mean z {:.2f} (p {:.3g}, needs > {:.3g}), {:.2f}% of pixel-channels pass (needs {:g}%)",
                               mean_z, mean_p, alpha_channel, pass_percent, s.min_pass_percent);
  return result;
}

}  // namespace farm
