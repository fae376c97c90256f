// threshold: OpenImageIO idiff's rule, so that `idiff` with the same flags gives the same verdict.
// Per pixel, a channel's error is |a - b|; it counts toward failing when it exceeds `fail` and
// (with fail_relative > 0) also that fraction of the mean of |a| and |b|; likewise warnings. As
// in idiff, an image without a failing pixel passes, so WARN means "some pixels fail, but fewer
// than fail_percent, and the warnings exceed warn_percent (or an error exceeds hard_warn)". A
// non-finite value matches a non-finite value of the same kind (NaN or inf); against anything
// else its error is infinite. One deliberate difference from idiff: idiff lets the first
// mismatched non-finite value raise the max error without counting its pixel as failing; here it
// fails its pixel like any other error above the threshold.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "renderer/compare/channel_pairs.h"
#include "renderer/compare/metrics.h"

namespace farm {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A value over an absolute and an optional relative threshold; written !(x <= t) as idiff does,
// so that a NaN error counts as over.
bool over(double error, double relative, double threshold, double relative_threshold) {
  return !(error <= threshold) && !(relative <= relative_threshold);
}

}  // namespace

CompareResult threshold_metric(const Image& reference, const Image& test, const CompareSettings& settings) {
  // idiff holds its thresholds as float: rounding ours the same way keeps a difference that
  // lands exactly on a threshold on the same side of it.
  CompareSettings s = settings;
  for (double* t : {&s.fail, &s.fail_relative, &s.fail_percent, &s.hard_fail, &s.warn, &s.warn_relative,
                    &s.warn_percent, &s.hard_warn})
    *t = static_cast<float>(*t);
  const std::vector<int> in_test = matching_channels(reference, test);
  const std::size_t pixel_count = reference.pixel_count();
  std::vector<double> pixel_error(pixel_count, 0.0);  // each pixel's largest channel error
  double total = 0.0, total_squared = 0.0, max_error = 0.0, peak = 1.0;
  std::size_t failing = 0, warning = 0, nonfinite = 0;
  int max_x = 0, max_y = 0, max_c = 0;
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      bool failed = false, warned = false;
      double& worst = pixel_error[static_cast<std::size_t>(y) * static_cast<std::size_t>(reference.width) +
                                  static_cast<std::size_t>(x)];
      for (std::size_t c = 0; c < in_test.size(); ++c) {
        const double a = reference.at(x, y, static_cast<int>(c)), b = test.at(x, y, in_test[c]);
        double error = 0.0, relative = 0.0;
        if (!std::isfinite(a) || !std::isfinite(b)) {
          if (std::isnan(a) == std::isnan(b) && std::isinf(a) == std::isinf(b)) continue;
          error = relative = kInfinity;
          ++nonfinite;
        } else {
          error = std::abs(a - b);
          const double mean_magnitude = 0.5 * (std::abs(a) + std::abs(b));
          relative = mean_magnitude > 0.0 ? error / mean_magnitude : 0.0;
          peak = std::max({peak, std::abs(a), std::abs(b)});
          total += error;
          total_squared += error * error;
        }
        if (error > max_error) max_error = error, max_x = x, max_y = y, max_c = static_cast<int>(c);
        worst = std::max(worst, error);
        if (!warned && over(error, relative, s.warn, s.warn_relative)) warned = true, ++warning;
        if (!failed && over(error, relative, s.fail, s.fail_relative)) failed = true, ++failing;
      }
    }
  const double values = static_cast<double>(pixel_count * in_test.size());
  const double mean_error = total / values, rms_error = std::sqrt(total_squared / values);
  const double psnr = rms_error > 0.0 ? 20.0 * std::log10(peak / rms_error) : kInfinity;
  const double pixels = static_cast<double>(pixel_count);

  CompareResult result;
  // idiff's order: no failing pixel at all is a PASS (warnings and hard limits notwithstanding);
  // then FAIL over fail_percent or hard_fail; then WARN over warn_percent or hard_warn.
  if (failing == 0) {
    result.verdict = Verdict::pass;
  } else if (static_cast<double>(failing) > s.fail_percent / 100.0 * pixels || max_error > s.hard_fail) {
    result.verdict = Verdict::fail;
  } else if (static_cast<double>(warning) > s.warn_percent / 100.0 * pixels || max_error > s.hard_warn) {
    result.verdict = Verdict::warn;
  } else {
    result.verdict = Verdict::pass;
  }
  result.figures = {{"mean_error", mean_error},
                    {"rms_error", rms_error},
                    {"psnr_db", psnr},
                    {"max_error", max_error},
                    {"max_x", static_cast<double>(max_x)},
                    {"max_y", static_cast<double>(max_y)},
                    {"failing_pixels", static_cast<double>(failing)},
                    {"failing_percent", 100.0 * static_cast<double>(failing) / pixels},
                    {"warning_pixels", static_cast<double>(warning)},
                    {"warning_percent", 100.0 * static_cast<double>(warning) / pixels},
                    {"nonfinite_mismatches", static_cast<double>(nonfinite)}};

  // The smallest `fail` that passes at this fail_percent: at most floor(fail_percent% of the
  // pixels) may lie above it, so it is the error of the pixel just past those (absolute errors;
  // a relative threshold can only let more pass).
  const auto allowed = static_cast<std::size_t>(std::floor(s.fail_percent / 100.0 * pixels));
  if (max_error > s.hard_fail) {
    result.would_pass_key = "hard_fail";
    result.would_pass_value = max_error;
  } else if (allowed < pixel_count) {
    std::nth_element(pixel_error.begin(), pixel_error.begin() + static_cast<std::ptrdiff_t>(allowed), pixel_error.end(),
                     std::greater<>());
    result.would_pass_key = "fail";
    result.would_pass_value = pixel_error[allowed];
  }
  result.summary = fmt::format("{} pixels ({:.3g}%) over fail {:g} (allowed {:g}%), max error {:.6g} at ({}, {}) {}, "
                               "mean {:.3g}, PSNR {:.2f} dB",
                               failing, result.figures[7].value, s.fail, s.fail_percent, max_error, max_x, max_y,
                               reference.channels[static_cast<std::size_t>(max_c)], mean_error, psnr);
  return result;
}

}  // namespace farm
