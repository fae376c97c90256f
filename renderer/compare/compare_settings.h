#pragma once
// What to compare with and how strictly: one metric and its thresholds. The names are the keys of
// a regression suite's "compare" object and, with dashes, the flags of `farm compare`; the
// threshold defaults are idiff's, so the same flags give the same verdict there.
#include <limits>
#include <optional>
#include <span>
#include <string_view>

namespace farm {

enum class Metric { exact, threshold, psnr, ssim, flip, ztest };
inline constexpr Metric kAllMetrics[] = {Metric::exact, Metric::threshold, Metric::psnr,
                                         Metric::ssim,  Metric::flip,      Metric::ztest};
std::string_view to_string(Metric metric);
std::optional<Metric> metric_from_string(std::string_view name);

enum class SsimChannels { luminance, each };  // SSIM of Rec. 709 luminance, or the mean over R G B

struct CompareSettings {
  Metric metric = Metric::threshold;
  // threshold (idiff): a pixel fails when a channel differs by more than `fail` and, when
  // `fail_relative` > 0, also by more than that fraction of the two values' mean magnitude. The
  // image fails when over `fail_percent` % of pixels fail or any error exceeds `hard_fail`;
  // likewise WARN.
  double fail = 1e-6, fail_relative = 0.0, fail_percent = 0.0;
  double hard_fail = std::numeric_limits<double>::infinity();
  double warn = 1e-6, warn_relative = 0.0, warn_percent = 0.0;
  double hard_warn = std::numeric_limits<double>::infinity();
  double min_psnr = 30.0;  // psnr: dB over the colour channels
  double min_ssim = 0.95;  // ssim: mean SSIM
  SsimChannels ssim_channels = SsimChannels::luminance;
  double max_mean = 0.05;                // flip: mean FLIP error
  double pixels_per_degree = 67.0206;    // flip: the viewer (FLIP's default)
  double alpha = 0.01;                   // ztest: significance, Sidak-corrected per value
  double min_pass_percent = 99.75;       // ztest: pixel-channels that must pass
  int threads = 0;                       // 0: all hardware threads
};

// A numeric threshold: its suite key (the `farm compare` flag is the key with dashes), the
// metric that reads it, the range a value must lie in, and what it means. The suite reader and
// the command line both walk this one table.
struct ThresholdKey {
  std::string_view name;
  double CompareSettings::*field;
  Metric metric;
  double min, max;
  std::string_view help;
};
std::span<const ThresholdKey> threshold_keys();
const ThresholdKey* find_threshold_key(std::string_view name);

std::string_view to_string(SsimChannels channels);  // luminance, each
std::optional<SsimChannels> ssim_channels_from_string(std::string_view name);

}  // namespace farm
