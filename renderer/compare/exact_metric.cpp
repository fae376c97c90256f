// exact: every channel of every pixel bit-identical, NaN payloads and signed zeros included.
#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#include "renderer/compare/channel_pairs.h"
#include "renderer/compare/metrics.h"

namespace farm {
namespace {

std::uint32_t bits_of(float v) {
  std::uint32_t b = 0;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

}  // namespace

CompareResult exact_metric(const Image& reference, const Image& test) {
  const std::vector<int> in_test = matching_channels(reference, test);
  std::size_t values = 0, pixels = 0;
  int first_x = -1, first_y = -1, first_c = -1;
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x) {
      bool pixel_differs = false;
      for (std::size_t c = 0; c < in_test.size(); ++c) {
        if (bits_of(reference.at(x, y, static_cast<int>(c))) == bits_of(test.at(x, y, in_test[c]))) continue;
        ++values;
        pixel_differs = true;
        if (first_x < 0) first_x = x, first_y = y, first_c = static_cast<int>(c);
      }
      pixels += pixel_differs ? 1 : 0;
    }
  CompareResult result;
  result.figures = {{"differing_pixels", static_cast<double>(pixels)},
                    {"differing_values", static_cast<double>(values)},
                    {"differing_percent", 100.0 * static_cast<double>(pixels) / static_cast<double>(reference.pixel_count())}};
  if (pixels == 0) {
    result.verdict = Verdict::pass;
    result.summary = fmt::format("bit-identical ({} channels)", reference.channel_count());
  } else {
    result.verdict = Verdict::fail;
    const auto c = static_cast<std::size_t>(first_c);
    result.summary = fmt::format("{} pixels ({:.3g}%) differ; the first at ({}, {}) {}: {} vs {}", pixels,
                                 result.figures[2].value, first_x, first_y, reference.channels[c],
                                 reference.at(first_x, first_y, first_c), test.at(first_x, first_y, in_test[c]));
  }
  return result;
}

}  // namespace farm
