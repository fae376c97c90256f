#pragma once
// An 8- or 16-bit image file's samples as read (PNG, JPEG), before anyone interprets them: each
// stored value scaled to [0, 1] (v / 255 or v / 65535), interleaved, rows top to bottom.
#include <cstddef>
#include <vector>

namespace farm {

struct DecodedImage {
  int width = 0;
  int height = 0;
  int channels = 0;  // 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA
  std::vector<float> values;
};

}  // namespace farm
