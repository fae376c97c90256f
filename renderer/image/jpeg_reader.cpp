#include "renderer/image/jpeg_reader.h"

#include <fmt/format.h>

#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "renderer/image/jpeg_error.h"


namespace farm {
namespace {

void on_jpeg_message(j_common_ptr, int) {}  // warnings (a corrupt-data recovery) change nothing we report

enum class Decoded { ok, failed, too_large, cmyk };

// Every libjpeg call that can fail happens below the setjmp. `pixels` is sized by the caller
// from the header, which this reads first: a second phase would need a second setjmp.
Decoded decode(jpeg_decompress_struct& cinfo, JpegError& error, std::FILE* in, int max_side,
               std::vector<std::uint8_t>& pixels, int& width, int& height, int& channels) {
  if (setjmp(error.jump) != 0) return Decoded::failed;
  jpeg_stdio_src(&cinfo, in);
  jpeg_read_header(&cinfo, TRUE);
  if (cinfo.image_width > static_cast<JDIMENSION>(max_side) || cinfo.image_height > static_cast<JDIMENSION>(max_side)) {
    width = static_cast<int>(cinfo.image_width);
    height = static_cast<int>(cinfo.image_height);
    return Decoded::too_large;
  }
  if (cinfo.jpeg_color_space == JCS_CMYK || cinfo.jpeg_color_space == JCS_YCCK) return Decoded::cmyk;
  cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&cinfo);
  width = static_cast<int>(cinfo.output_width);
  height = static_cast<int>(cinfo.output_height);
  channels = cinfo.output_components;
  const std::size_t stride = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  pixels.resize(stride * static_cast<std::size_t>(height));
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = pixels.data() + static_cast<std::size_t>(cinfo.output_scanline) * stride;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  return Decoded::ok;
}

// libjpeg's errors come back to `error` (a longjmp to its jump buffer), its warnings are dropped.
void start_decompress(jpeg_decompress_struct& cinfo, JpegError& error) {
  cinfo.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = on_jpeg_error;
  error.manager.emit_message = on_jpeg_message;
  cinfo.client_data = &error;
  jpeg_create_decompress(&cinfo);
}

bool read_header_size(jpeg_decompress_struct& cinfo, JpegError& error, std::FILE* in, int& width, int& height) {
  if (setjmp(error.jump) != 0) return false;
  jpeg_stdio_src(&cinfo, in);
  jpeg_read_header(&cinfo, TRUE);
  width = static_cast<int>(cinfo.image_width);
  height = static_cast<int>(cinfo.image_height);
  return true;
}

}  // namespace

std::pair<int, int> read_jpeg_size(std::FILE* in, const std::filesystem::path& name) {
  jpeg_decompress_struct cinfo{};
  JpegError error;
  start_decompress(cinfo, error);
  int width = 0, height = 0;
  const bool read = read_header_size(cinfo, error, in, width, height);
  jpeg_destroy_decompress(&cinfo);
  if (!read) throw std::runtime_error(fmt::format("{}: cannot read JPEG: {}", name.string(), error.message));
  return {width, height};
}

DecodedImage read_jpeg(std::FILE* in, const std::filesystem::path& name, int max_side) {
  jpeg_decompress_struct cinfo{};
  JpegError error;
  start_decompress(cinfo, error);
  std::vector<std::uint8_t> pixels;
  int width = 0, height = 0, channels = 0;
  const Decoded result = decode(cinfo, error, in, max_side, pixels, width, height, channels);
  jpeg_destroy_decompress(&cinfo);
  switch (result) {
    case Decoded::failed:
      throw std::runtime_error(fmt::format("{}: cannot read JPEG: {}", name.string(), error.message));
    case Decoded::too_large:
      throw std::runtime_error(fmt::format("{}: cannot read JPEG: {}x{} is larger than {} pixels a side",
                                           name.string(), width, height, max_side));
    case Decoded::cmyk:
      throw std::runtime_error(fmt::format("{}: cannot read JPEG: CMYK images are not supported", name.string()));
    case Decoded::ok: break;
  }
  DecodedImage image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.values.resize(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) image.values[i] = static_cast<float>(pixels[i]) / 255.0f;
  return image;
}

}  // namespace farm
