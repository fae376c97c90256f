#pragma once
// How the PNG reader and writer take libpng's errors: libpng calls the handler, which must not
// return, so it longjmps back below a setjmp in a frame that holds nothing with a destructor; the
// message waits here, in plain storage, for the C++ side to throw it.
#include <png.h>

#include <cstdio>

namespace farm {

struct PngError {
  char message[256] = "";
};

inline void on_png_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof error->message, "%s", message);
  png_longjmp(png, 1);
}

}  // namespace farm
