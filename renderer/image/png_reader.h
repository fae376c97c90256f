#pragma once
// PNG files through libpng, read as stored (palette and low bit depths expanded, 16 bit kept).
#include <cstdio>
#include <filesystem>

#include "renderer/image/decoded_image.h"

namespace farm {

// Reads the PNG in `in`. Images wider or taller than `max_side` are refused before their pixels
// are read. Throws std::runtime_error naming `name` (what the caller knows `in` as).
DecodedImage read_png(std::FILE* in, const std::filesystem::path& name, int max_side);

}  // namespace farm
