#include "renderer/compare/compare.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

#include "renderer/compare/metrics.h"

namespace farm {
namespace {

CompareResult cannot_compare(Metric metric, std::string reason) {
  CompareResult result;
  result.metric = metric;
  result.verdict = Verdict::fail;
  result.summary = std::move(reason);
  return result;
}

std::vector<std::string> sorted(std::vector<std::string> names) {
  std::sort(names.begin(), names.end());
  return names;
}

// Why two images cannot be compared by `metric`, or empty when they can.
std::string incompatibility(const Image& reference, const Image& test, Metric metric) {
  if (reference.width != test.width || reference.height != test.height) {
    return fmt::format("sizes differ: reference {}x{}, new {}x{}", reference.width, reference.height, test.width,
                       test.height);
  }
  if (reference.pixel_count() == 0) return "the images are empty";
  if (metric == Metric::exact || metric == Metric::threshold) {
    // Every channel is compared, matched by name: both must hold the same set.
    if (sorted(reference.channels) != sorted(test.channels)) {
      return fmt::format("channels differ: reference {}, new {}", fmt::join(reference.channels, " "),
                         fmt::join(test.channels, " "));
    }
    return {};
  }
  const std::vector<int> a = colour_channels(reference), b = colour_channels(test);
  if (a.empty() || b.empty()) return "no colour channels (R G B, or Y) to compare";
  if (a.size() != b.size()) return "one image is grey and the other colour";
  if (reference.display_referred != test.display_referred) {
    return "one image is an 8-bit PNG/JPEG (sRGB-encoded) and the other a linear EXR";
  }
  return {};
}

}  // namespace

std::string_view to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::pass: return "PASS";
    case Verdict::warn: return "WARN";
    case Verdict::fail: return "FAIL";
  }
  return "?";
}

double CompareResult::figure(std::string_view name) const {
  for (const Figure& f : figures)
    if (f.name == name) return f.value;
  return std::numeric_limits<double>::quiet_NaN();
}

CompareResult compare_images(const Image& reference, const Image& test, const CompareSettings& settings) {
  if (std::string why = incompatibility(reference, test, settings.metric); !why.empty()) {
    return cannot_compare(settings.metric, std::move(why));
  }
  CompareResult result;
  switch (settings.metric) {
    case Metric::exact: result = exact_metric(reference, test); break;
    case Metric::threshold: result = threshold_metric(reference, test, settings); break;
    case Metric::psnr: result = psnr_metric(reference, test, settings); break;
    case Metric::ssim: result = ssim_metric(reference, test, settings); break;
    case Metric::flip: result = flip_metric(reference, test, settings); break;
    case Metric::ztest: result = ztest_metric(reference, test, settings); break;
  }
  result.metric = settings.metric;
  // FLIP and the z-test make their own maps; every other metric shows |a - b| x16.
  const std::size_t colours = colour_channels(reference).size();
  if (result.difference.pixel_count() == 0 && colours > 0 && colours == colour_channels(test).size()) {
    result.difference = absolute_difference_x16(reference, test);
  }
  return result;
}

}  // namespace farm
