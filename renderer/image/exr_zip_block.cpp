#include "renderer/image/exr_zip_block.h"

#include <algorithm>
#include <cstring>

#include "renderer/image/float_to_half.h"
#include "renderer/image/zlib_stream.h"
#include "renderer/util/uninitialized_array.h"

namespace farm {

std::size_t exr_line_bytes(const std::vector<ExrChannel>& channels, int width) {
  std::size_t bytes = 0;
  for (const ExrChannel& c : channels) bytes += static_cast<std::size_t>(width) * (c.half ? 2 : 4);
  return bytes;
}

namespace {

// The line's bytes go straight into the two halves of the split: a value at byte offset o of the
// unpacked chunk (always even: values are 2 or 4 bytes) puts its bytes 0 and 2 at o/2 and o/2 + 1
// of the first half, its bytes 1 and 3 there in the second.
void split_lines(const std::vector<ExrChannel>& channels, std::size_t width, int y0, int y1, std::uint8_t* even,
                 std::uint8_t* odd) {
  for (int y = y0; y < y1; ++y) {
    for (const ExrChannel& c : channels) {
      const char* first = c.first + static_cast<std::size_t>(y) * c.row_stride;
      if (c.half) {
        std::uint16_t halves[256];
        for (std::size_t x = 0; x < width; x += 256) {
          const std::size_t count = std::min<std::size_t>(256, width - x);
          floats_to_halves(first + x * c.stride, c.stride, count, halves);
          for (std::size_t i = 0; i < count; ++i) {  // little-endian halves, as the file wants
            even[i] = static_cast<std::uint8_t>(halves[i]);
            odd[i] = static_cast<std::uint8_t>(halves[i] >> 8);
          }
          even += count;
          odd += count;
        }
      } else {
        for (std::size_t x = 0; x < width; ++x, even += 2, odd += 2) {
          std::uint8_t bytes[4];
          std::memcpy(bytes, first + x * c.stride, 4);
          even[0] = bytes[0];
          odd[0] = bytes[1];
          even[1] = bytes[2];
          odd[1] = bytes[3];
        }
      }
    }
  }
}

}  // namespace

std::vector<std::uint8_t> pack_zip_chunk(const std::vector<ExrChannel>& channels, int width, int y0, int y1) {
  const std::size_t n = exr_line_bytes(channels, width) * static_cast<std::size_t>(y1 - y0);  // even
  thread_local UninitializedArray<std::uint8_t> scratch;  // reused: no fresh pages a chunk
  scratch.allocate(std::max<std::size_t>(2 * n, 1));
  std::uint8_t* split = scratch.begin();
  std::uint8_t* predicted = split + n;
  split_lines(channels, static_cast<std::size_t>(width), y0, y1, split, split + n / 2);
  // Each byte as its difference to the one before it, plus 128.
  if (n > 0) predicted[0] = split[0];
  for (std::size_t i = 1; i < n; ++i) predicted[i] = static_cast<std::uint8_t>(split[i] - split[i - 1] + 128);
  std::vector<std::uint8_t> out;
  // Only a stream shorter than the lines is kept (a reader tells the two apart by the size);
  // otherwise the lines themselves, interleaved again from the split (rare: noise).
  if (n > 0 && zlib_compress({predicted, n}, out, n - 1)) return out;
  out.resize(n);
  for (std::size_t i = 0; i < n / 2; ++i) {
    out[2 * i] = split[i];
    out[2 * i + 1] = split[n / 2 + i];
  }
  return out;
}

}  // namespace farm
