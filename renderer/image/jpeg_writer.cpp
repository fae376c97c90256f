#include "renderer/image/jpeg_writer.h"

#include <fmt/format.h>

#include <csetjmp>
#include <cstddef>
#include <cstdio>
#include <stdexcept>

#include "renderer/image/jpeg_error.h"

namespace farm {
namespace {

constexpr int kQuality = 98;

// Every libjpeg call that can fail happens in here, below the setjmp: a longjmp then skips only
// libjpeg's own C frames and lands in a frame that holds nothing with a destructor. Returns false
// after an error (its message is in the JpegError).
bool encode(jpeg_compress_struct& cinfo, JpegError& error, const Rgb8Rows& image, std::FILE* out) {
  if (setjmp(error.jump) != 0) return false;
  jpeg_create_compress(&cinfo);
  jpeg_stdio_dest(&cinfo, out);
  cinfo.image_width = static_cast<JDIMENSION>(image.width);
  cinfo.image_height = static_cast<JDIMENSION>(image.height);
  cinfo.input_components = 3;
  cinfo.in_color_space = JCS_RGB;
  jpeg_set_defaults(&cinfo);  // among them 4:2:0 chroma subsampling
  jpeg_set_quality(&cinfo, kQuality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  while (cinfo.next_scanline < cinfo.image_height) {
    // libjpeg's API takes rows as non-const; compression only reads them.
    JSAMPROW row = const_cast<JSAMPROW>(image.row(static_cast<int>(cinfo.next_scanline)));
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  return true;
}

// Owns libjpeg's compressor for one file. Zeroed, so destroying one whose creation failed is safe.
struct JpegCompressor {
  jpeg_compress_struct cinfo{};
  JpegError error;

  JpegCompressor() {
    cinfo.err = jpeg_std_error(&error.manager);
    error.manager.error_exit = on_jpeg_error;
    cinfo.client_data = &error;
  }
  ~JpegCompressor() { jpeg_destroy_compress(&cinfo); }
  JpegCompressor(const JpegCompressor&) = delete;
  JpegCompressor& operator=(const JpegCompressor&) = delete;
};

}  // namespace

void write_jpeg(const Rgb8Image& image, std::FILE* out, const std::filesystem::path& name) {
  write_jpeg(rows_of(image), out, name);
}

void write_jpeg(const Rgb8Rows& image, std::FILE* out, const std::filesystem::path& name) {
  JpegCompressor compressor;
  if (!encode(compressor.cinfo, compressor.error, image, out)) {
    throw std::runtime_error(fmt::format("{}: cannot write JPEG: {}", name.string(), compressor.error.message));
  }
}

}  // namespace farm
