#pragma once
// JPEG files through libjpeg (libjpeg-turbo on Debian), decoded to grey or RGB.
#include <cstdio>
#include <filesystem>
#include <utility>

#include "renderer/image/decoded_image.h"

namespace farm {

// Reads the JPEG in `in`. Images wider or taller than `max_side` are refused before their
// pixels are decoded; CMYK JPEGs are refused. Throws std::runtime_error naming `name`.
DecodedImage read_jpeg(std::FILE* in, const std::filesystem::path& name, int max_side);

// The width and height its header says, nothing decoded. Throws std::runtime_error naming `name`.
std::pair<int, int> read_jpeg_size(std::FILE* in, const std::filesystem::path& name);

}  // namespace farm
