// The one place that calls OpenImageIO. It is built as a module of its own and opened on first use
// (preview_writer.cpp) rather than linked into `farm`: OpenImageIO brings about 260 shared
// libraries, and binding them cost every start of `farm` and of each test 0.3 s, although only the
// PNG preview needs them. A C interface keeps the boundary free of C++ ABI concerns.
#include <OpenImageIO/imageio.h>

#include <cstddef>
#include <cstdio>
#include <string>

#include "renderer/image/oiio_preview_module.h"

namespace {

void set_error(char* error, std::size_t error_size, const std::string& message) {
  if (error_size > 0) std::snprintf(error, error_size, "%s", message.c_str());
}

}  // namespace

extern "C" {

int farm_preview_can_write(const char* path) { return OIIO::ImageOutput::create(path) != nullptr ? 1 : 0; }

int farm_preview_write_rgb8(const char* path, int width, int height, const unsigned char* pixels, char* error,
                            std::size_t error_size) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) {
    set_error(error, error_size, "no image writer for this extension (" + OIIO::geterror() + ")");
    return 0;
  }
  OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  // Previews of noisy renders: zlib level 1 writes a 512x512 one in 23 ms instead of 32, 3% larger.
  spec.attribute("png:compressionLevel", 1);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, pixels) || !out->close()) {
    set_error(error, error_size, out->geterror());
    return 0;
  }
  return 1;
}

}  // extern "C"
