// psnr: peak signal-to-noise ratio of the colour channels, 20 log10(peak / RMS error), with
// idiff's peak: 1, or the largest magnitude in either image when that is larger (HDR).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "renderer/compare/metrics.h"

namespace farm {

CompareResult psnr_metric(const Image& reference, const Image& test, const CompareSettings& s) {
  const std::vector<int> a_channels = colour_channels(reference), b_channels = colour_channels(test);
  double squared = 0.0, peak = 1.0;
  std::size_t nonfinite = 0;
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x)
      for (std::size_t c = 0; c < a_channels.size(); ++c) {
        const double a = reference.at(x, y, a_channels[c]), b = test.at(x, y, b_channels[c]);
        if (!std::isfinite(a) || !std::isfinite(b)) {
          nonfinite += (std::isnan(a) == std::isnan(b) && std::isinf(a) == std::isinf(b)) ? 0 : 1;
          continue;
        }
        squared += (a - b) * (a - b);
        peak = std::max({peak, std::abs(a), std::abs(b)});
      }
  const double values = static_cast<double>(reference.pixel_count() * a_channels.size());
  const double rms = nonfinite > 0 ? std::numeric_limits<double>::infinity() : std::sqrt(squared / values);
  const double psnr = rms > 0.0 ? 20.0 * std::log10(peak / rms) : std::numeric_limits<double>::infinity();

  CompareResult result;
  result.verdict = psnr >= s.min_psnr ? Verdict::pass : Verdict::fail;
  result.figures = {{"psnr_db", psnr}, {"rms_error", rms}, {"peak", peak}, {"nonfinite_mismatches", static_cast<double>(nonfinite)}};
  result.would_pass_key = "min_psnr";
  result.would_pass_value = psnr;
  result.summary = fmt::format("PSNR {:.2f} dB (needs {:g}), RMS error {:.4g}", psnr, s.min_psnr, rms);
  if (nonfinite > 0) result.summary += fmt::format(", {} NaN/inf values where the other image has a number", nonfinite);
  return result;
}

}  // namespace farm
