// The plain difference image: |reference - new| x16 of the colour channels, so that an error of
// 1/16 shows white, as the difference images of Blender's render tests are scaled.
#include <cmath>

#include "renderer/compare/metrics.h"

namespace farm {

Image absolute_difference_x16(const Image& reference, const Image& test) {
  const std::vector<int> a = colour_channels(reference), b = colour_channels(test);
  Image out = make_image(reference.width, reference.height, {"R", "G", "B"});
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x)
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t from = a.size() == 1 ? 0 : c;
        const float d = std::abs(reference.at(x, y, a[from]) - test.at(x, y, b[from]));
        out.at(x, y, static_cast<int>(c)) = std::isnan(d) ? 1.0f : 16.0f * d;  // NaN against a number shows white
      }
  return out;
}

}  // namespace farm
