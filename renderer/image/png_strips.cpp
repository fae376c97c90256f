#include "renderer/image/png_strips.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "renderer/image/zlib_stream.h"
#include "renderer/util/uninitialized_array.h"

namespace farm {
namespace {

constexpr std::uint8_t kFilterSub = 1;
constexpr std::uint8_t kFilterUp = 2;

// A chunk's length field holds at most 2^31 - 1.
constexpr std::size_t kMaxChunkBytes = 0x7FFFFFFF;

class ChunkWriter {
 public:
  ChunkWriter(std::FILE* out, const std::filesystem::path& name) : out_(out), name_(name) {}

  void bytes(const std::uint8_t* data, std::size_t size) {
    if (size > 0 && std::fwrite(data, 1, size, out_) != size) {
      const int error = errno != 0 ? errno : EIO;
      throw std::system_error(error, std::generic_category(),
                              fmt::format("{}: cannot write PNG", name_.string()));
    }
  }

  // One chunk: its length, type and data (in parts, one after the other), and the CRC of the type
  // and data.
  void chunk(std::string_view type, std::initializer_list<std::span<const std::uint8_t>> parts) {
    std::size_t length = 0;
    for (const auto& part : parts) length += part.size();
    if (length > kMaxChunkBytes) {
      throw std::runtime_error(fmt::format("{}: cannot write PNG: a chunk of {} bytes", name_.string(), length));
    }
    std::vector<std::uint8_t> head;
    append_big_endian(static_cast<std::uint32_t>(length), head);
    head.insert(head.end(), type.begin(), type.end());
    std::uint32_t crc = crc32_of(std::span(head).subspan(4));
    for (const auto& part : parts) crc = crc32_of(part, crc);
    bytes(head.data(), head.size());
    for (const auto& part : parts) bytes(part.data(), part.size());
    std::vector<std::uint8_t> tail;
    append_big_endian(crc, tail);
    bytes(tail.data(), tail.size());
  }

 private:
  std::FILE* out_;
  const std::filesystem::path& name_;
};

std::vector<std::uint8_t> big_endian(std::initializer_list<std::uint32_t> values) {
  std::vector<std::uint8_t> out;
  for (std::uint32_t v : values) append_big_endian(v, out);
  return out;
}

}  // namespace

PngStrips::PngStrips(int width, int height, const std::filesystem::path& name)
    : width_(width), height_(height), name_(name) {
  if (width <= 0 || height <= 0) {
    throw std::runtime_error(fmt::format("{}: cannot write PNG: an image of {}x{} pixels", name.string(), width, height));
  }
  strips_.resize(static_cast<std::size_t>((height + kRows - 1) / kRows));
}

int PngStrips::end_row(int strip) const { return std::min(height_, (strip + 1) * kRows); }

void PngStrips::compress(int strip, const std::function<const std::uint8_t*(int y)>& row) {
  const std::size_t row_bytes = static_cast<std::size_t>(width_) * 3;
  const int y0 = first_row(strip), y1 = end_row(strip);
  thread_local UninitializedArray<std::uint8_t> filtered;  // reused: no fresh pages a strip
  filtered.allocate((row_bytes + 1) * static_cast<std::size_t>(y1 - y0));
  std::uint8_t* at = filtered.begin();
  const std::uint8_t* above = nullptr;
  for (int y = y0; y < y1; ++y) {
    const std::uint8_t* line = row(y);
    if (above == nullptr) {
      *at++ = kFilterSub;
      for (std::size_t i = 0; i < 3; ++i) at[i] = line[i];
      for (std::size_t i = 3; i < row_bytes; ++i) at[i] = static_cast<std::uint8_t>(line[i] - line[i - 3]);
    } else {
      *at++ = kFilterUp;
      for (std::size_t i = 0; i < row_bytes; ++i) at[i] = static_cast<std::uint8_t>(line[i] - above[i]);
    }
    at += row_bytes;
    above = line;
  }
  Strip& s = strips_[static_cast<std::size_t>(strip)];
  s.deflated.clear();
  if (strip == 0) {
    const auto header = zlib_header();
    s.deflated.assign(header.begin(), header.end());
  }
  const bool last = strip + 1 == strips();
  const std::span<const std::uint8_t> rows(filtered.begin(), filtered.size());
  if (!deflate_piece(rows, last, s.deflated, deflate_limit(rows.size()))) {
    throw std::runtime_error(fmt::format("{}: cannot write PNG: could not compress rows {} to {}",
                                         name_.string(), y0, y1 - 1));
  }
  s.adler = adler32_of(rows);
  s.filtered_bytes = rows.size();
}

void PngStrips::write(std::FILE* out) const {
  ChunkWriter file(out, name_);
  constexpr std::array<std::uint8_t, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  file.bytes(kSignature.data(), kSignature.size());
  std::vector<std::uint8_t> header = big_endian({static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_)});
  // 8 bits a sample, colour type 2 (RGB), deflate, adaptive filtering, no interlace.
  header.insert(header.end(), {8, 2, 0, 0, 0});
  file.chunk("IHDR", {header});
  const std::uint8_t perceptual = 0;
  file.chunk("sRGB", {std::span(&perceptual, 1)});
  // The gamma and chromaticities sRGB implies (in 1/100000), for readers that ignore sRGB.
  file.chunk("gAMA", {big_endian({45455})});
  file.chunk("cHRM", {big_endian({31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000})});
  std::uint32_t adler = 1;
  for (const Strip& s : strips_) adler = adler32_join(adler, s.adler, s.filtered_bytes);
  const std::vector<std::uint8_t> checksum = big_endian({adler});
  for (std::size_t k = 0; k < strips_.size(); ++k) {
    if (strips_[k].deflated.empty()) {
      throw std::logic_error(fmt::format("{}: PNG strip {} was never compressed", name_.string(), k));
    }
    const bool last = k + 1 == strips_.size();
    file.chunk("IDAT", {strips_[k].deflated, last ? std::span<const std::uint8_t>(checksum) : std::span<const std::uint8_t>()});
  }
  file.chunk("IEND", {});
}

}  // namespace farm
