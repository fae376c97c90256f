#include "renderer/image/exr_zip_block.h"

#include <cstring>

#include "renderer/image/float_to_half.h"
#include "renderer/image/zlib_stream.h"

namespace farm {

std::size_t exr_line_bytes(const std::vector<ExrChannel>& channels, int width) {
  std::size_t bytes = 0;
  for (const ExrChannel& c : channels) bytes += static_cast<std::size_t>(width) * (c.half ? 2 : 4);
  return bytes;
}

std::vector<std::uint8_t> pack_zip_chunk(const std::vector<ExrChannel>& channels, int width, int y0, int y1,
                                         int level, std::vector<std::uint8_t>& scratch) {
  const std::size_t line = exr_line_bytes(channels, width);
  const std::size_t n = line * static_cast<std::size_t>(y1 - y0);
  scratch.resize(2 * n);
  std::uint8_t* raw = scratch.data();
  std::uint8_t* split = raw + n;
  // The lines as the file lays them out: channel after channel, each a run of the line's values.
  std::uint8_t* at = raw;
  const auto w = static_cast<std::size_t>(width);
  for (int y = y0; y < y1; ++y) {
    for (const ExrChannel& c : channels) {
      const char* first = c.first + static_cast<std::size_t>(y) * c.row_stride;
      if (c.half) {
        std::uint16_t halves[256];
        // Through a small aligned buffer: the chunk's own bytes need not be aligned for uint16.
        for (std::size_t x = 0; x < w; x += 256) {
          const std::size_t count = std::min<std::size_t>(256, w - x);
          floats_to_halves(first + x * c.stride, c.stride, count, halves);
          std::memcpy(at, halves, count * 2);  // little-endian, as the file wants (x86-64)
          at += count * 2;
        }
      } else {
        for (std::size_t x = 0; x < w; ++x, at += 4) std::memcpy(at, first + x * c.stride, 4);
      }
    }
  }
  // Even bytes, then odd bytes; then each byte as its difference to the one before it.
  const std::size_t half = (n + 1) / 2;
  for (std::size_t i = 0; i < n / 2; ++i) {
    split[i] = raw[2 * i];
    split[half + i] = raw[2 * i + 1];
  }
  if (n % 2 != 0) split[half - 1] = raw[n - 1];
  // Predicted in place, from the end, so that the unpacked lines stay for a chunk stored raw.
  for (std::size_t i = n; i-- > 1;) split[i] = static_cast<std::uint8_t>(split[i] - split[i - 1] + 128);
  std::vector<std::uint8_t> out;
  // Only a stream shorter than the lines is kept (a reader tells the two apart by the size).
  if (n == 0 || !zlib_compress({split, n}, level, out, n - 1)) out.assign(raw, raw + n);
  return out;
}

}  // namespace farm
