#include "renderer/image/png_reader.h"

#include <fmt/format.h>
#include <png.h>

#include <array>
#include <csetjmp>
#include <cstring>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "renderer/image/png_error.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

void on_png_warning(png_structp, png_const_charp) {}  // a warning changes nothing we read

class PngReadStruct {
 public:
  explicit PngReadStruct(PngError& error)
      : png_(png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, on_png_error, on_png_warning)),
        info_(png_ != nullptr ? png_create_info_struct(png_) : nullptr) {}
  ~PngReadStruct() { png_destroy_read_struct(&png_, &info_, nullptr); }
  PngReadStruct(const PngReadStruct&) = delete;
  PngReadStruct& operator=(const PngReadStruct&) = delete;

  bool created() const { return info_ != nullptr; }
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_;
  png_infop info_;
};

// The header: size and layout after the expansions asked for. Returns false after a libpng error.
bool read_header(png_structp png, png_infop info, std::FILE* in, int max_side, png_uint_32& width,
                 png_uint_32& height, int& channels, int& bit_depth) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_init_io(png, in);
  // libpng refuses larger images itself, before allocating anything for them.
  png_set_user_limits(png, static_cast<png_uint_32>(max_side), static_cast<png_uint_32>(max_side));
  png_read_info(png, info);
  png_set_expand(png);  // palette -> RGB, grey below 8 bits -> 8, tRNS -> alpha
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  width = png_get_image_width(png, info);
  height = png_get_image_height(png, info);
  channels = png_get_channels(png, info);
  bit_depth = png_get_bit_depth(png, info);
  return true;
}

bool read_rows(png_structp png, png_infop info, std::vector<png_bytep>& rows) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_read_image(png, rows.data());
  png_read_end(png, info);
  return true;
}

}  // namespace

DecodedImage read_png(std::FILE* in, const std::filesystem::path& name, int max_side) {
  PngError error;
  PngReadStruct read(error);
  if (!read.created()) throw std::runtime_error(fmt::format("{}: cannot read PNG: libpng failed to start", name.string()));
  png_uint_32 width = 0, height = 0;
  int channels = 0, bit_depth = 0;
  if (!read_header(read.png(), read.info(), in, max_side, width, height, channels, bit_depth)) {
    throw std::runtime_error(fmt::format("{}: cannot read PNG: {}", name.string(), error.message));
  }
  if (channels < 1 || channels > 4 || (bit_depth != 8 && bit_depth != 16)) {
    throw std::runtime_error(
        fmt::format("{}: cannot read PNG: {} channels of {} bits are not supported", name.string(), channels, bit_depth));
  }
  const std::size_t bytes_per_sample = static_cast<std::size_t>(bit_depth / 8);
  const std::size_t row_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels) * bytes_per_sample;
  std::vector<std::uint8_t> bytes(row_bytes * height);
  std::vector<png_bytep> rows(height);
  for (std::size_t y = 0; y < height; ++y) rows[y] = bytes.data() + y * row_bytes;
  if (!read_rows(read.png(), read.info(), rows)) {
    throw std::runtime_error(fmt::format("{}: cannot read PNG: {}", name.string(), error.message));
  }

  DecodedImage image;
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  image.channels = channels;
  image.values.resize(bytes.size() / bytes_per_sample);
  if (bit_depth == 8) {
    for (std::size_t i = 0; i < image.values.size(); ++i) image.values[i] = static_cast<float>(bytes[i]) / 255.0f;
  } else {  // 16-bit samples are stored big-endian
    for (std::size_t i = 0; i < image.values.size(); ++i) {
      const unsigned value = (static_cast<unsigned>(bytes[2 * i]) << 8) | bytes[2 * i + 1];
      image.values[i] = static_cast<float>(value) / 65535.0f;
    }
  }
  return image;
}

// A PNG's IHDR, which the format puts first: the size without libpng's decoder set up.
std::pair<int, int> read_png_size(std::FILE* in, const std::filesystem::path& file) {
  std::array<unsigned char, 24> head{};
  const std::size_t got = std::fread(head.data(), 1, head.size(), in);
  std::rewind(in);
  if (got < head.size() || std::memcmp(head.data() + 12, "IHDR", 4) != 0) {
    throw InputError(fmt::format("{}: cannot read PNG: no IHDR chunk first", file.string()));
  }
  const auto be32 = [&](std::size_t at) {
    return (std::uint32_t{head[at]} << 24) | (std::uint32_t{head[at + 1]} << 16) | (std::uint32_t{head[at + 2]} << 8) |
           std::uint32_t{head[at + 3]};
  };
  const std::uint32_t width = be32(16), height = be32(20);
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) {
    throw InputError(fmt::format("{}: cannot read PNG: a {}x{} image", file.string(), width, height));
  }
  return {static_cast<int>(width), static_cast<int>(height)};
}


}  // namespace farm
