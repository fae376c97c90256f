#pragma once
// A preview's pixels once they are 8-bit: what the PNG and JPEG writers are handed.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace farm {

struct Rgb8Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // R G B per pixel, rows top to bottom, no padding
};

// An image's rows as a writer takes them, one at a time from the top: a whole Rgb8Image, or a
// preview whose rows are still being made (StreamedPreview), for which row(y) waits for row y.
struct Rgb8Rows {
  int width = 0;
  int height = 0;
  std::function<const std::uint8_t*(int y)> row;  // width x RGB; may throw to stop the writer
};

inline Rgb8Rows rows_of(const Rgb8Image& image) {
  return {image.width, image.height, [&image](int y) {
            return image.pixels.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(image.width) * 3;
          }};
}

}  // namespace farm
