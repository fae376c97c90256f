#pragma once
// A preview's pixels once they are 8-bit: what the PNG and JPEG writers are handed.
#include <cstdint>
#include <vector>

namespace farm {

struct Rgb8Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // R G B per pixel, rows top to bottom, no padding
};

}  // namespace farm
