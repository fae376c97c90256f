#include "renderer/compare/compare_settings.h"

#include <array>

namespace farm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

constexpr std::array<ThresholdKey, 14> kKeys = {{
    {"fail", &CompareSettings::fail, Metric::threshold, 0.0, kInf,
     "a pixel fails when a channel differs by more than this (idiff -fail)"},
    {"fail_relative", &CompareSettings::fail_relative, Metric::threshold, 0.0, kInf,
     "...and by more than this fraction of the values' mean magnitude (idiff -failrelative)"},
    {"fail_percent", &CompareSettings::fail_percent, Metric::threshold, 0.0, 100.0,
     "FAIL when more than this percentage of pixels fail (idiff -failpercent)"},
    {"hard_fail", &CompareSettings::hard_fail, Metric::threshold, 0.0, kInf,
     "FAIL when any error exceeds this (idiff -hardfail)"},
    {"warn", &CompareSettings::warn, Metric::threshold, 0.0, kInf, "the same for WARN (idiff -warn)"},
    {"warn_relative", &CompareSettings::warn_relative, Metric::threshold, 0.0, kInf, "idiff -warnrelative"},
    {"warn_percent", &CompareSettings::warn_percent, Metric::threshold, 0.0, 100.0, "idiff -warnpercent"},
    {"hard_warn", &CompareSettings::hard_warn, Metric::threshold, 0.0, kInf, "idiff -hardwarn"},
    {"min_psnr", &CompareSettings::min_psnr, Metric::psnr, -kInf, kInf, "PASS at or above this PSNR, in dB"},
    {"min_ssim", &CompareSettings::min_ssim, Metric::ssim, -1.0, 1.0, "PASS at or above this mean SSIM"},
    {"max_mean", &CompareSettings::max_mean, Metric::flip, 0.0, 1.0, "PASS at or below this mean FLIP error"},
    {"pixels_per_degree", &CompareSettings::pixels_per_degree, Metric::flip, 1.0, 1000.0,
     "FLIP's viewer: pixels per degree of visual angle (default 67.0206)"},
    {"alpha", &CompareSettings::alpha, Metric::ztest, 1e-12, 0.5,
     "z-test significance level (Sidak-corrected per pixel-channel; also the image mean's test)"},
    {"min_pass_percent", &CompareSettings::min_pass_percent, Metric::ztest, 0.0, 100.0,
     "z-test: the percentage of pixel-channels that must pass"},
}};

}  // namespace

std::span<const ThresholdKey> threshold_keys() { return kKeys; }

const ThresholdKey* find_threshold_key(std::string_view name) {
  for (const ThresholdKey& key : kKeys)
    if (key.name == name) return &key;
  return nullptr;
}

std::string_view to_string(Metric metric) {
  switch (metric) {
    case Metric::exact: return "exact";
    case Metric::threshold: return "threshold";
    case Metric::psnr: return "psnr";
    case Metric::ssim: return "ssim";
    case Metric::flip: return "flip";
    case Metric::ztest: return "ztest";
  }
  return "?";
}

std::optional<Metric> metric_from_string(std::string_view name) {
  for (Metric m : kAllMetrics)
    if (to_string(m) == name) return m;
  return std::nullopt;
}

std::string_view to_string(SsimChannels channels) {
  return channels == SsimChannels::luminance ? "luminance" : "each";
}

std::optional<SsimChannels> ssim_channels_from_string(std::string_view name) {
  if (name == "luminance") return SsimChannels::luminance;
  if (name == "each") return SsimChannels::each;
  return std::nullopt;
}

}  // namespace farm
