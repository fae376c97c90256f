#pragma once
// The C interface of the preview module (oiio_preview_module.cpp), looked up by name with dlsym.
#include <cstddef>

extern "C" {

// 1 when OpenImageIO has a writer for the file's extension.
int farm_preview_can_write(const char* path);
using FarmPreviewCanWrite = int (*)(const char*);

// Writes 8-bit sRGB RGB pixels, rows top to bottom; 1 on success, else 0 with a message in `error`.
int farm_preview_write_rgb8(const char* path, int width, int height, const unsigned char* pixels, char* error,
                            std::size_t error_size);
using FarmPreviewWriteRgb8 = int (*)(const char*, int, int, const unsigned char*, char*, std::size_t);

}  // extern "C"
