#pragma once
// PNG files through libpng, read as stored (palette and low bit depths expanded, 16 bit kept).
#include <cstdio>
#include <filesystem>
#include <utility>

#include "renderer/image/decoded_image.h"

namespace farm {

// Reads the PNG in `in`. Images wider or taller than `max_side` are refused before their pixels
// are read. Throws std::runtime_error naming `name` (what the caller knows `in` as).
DecodedImage read_png(std::FILE* in, const std::filesystem::path& name, int max_side);

// The width and height its IHDR says (the format puts it first), nothing decoded; rewinds `in`.
// Throws InputError naming `name`.
std::pair<int, int> read_png_size(std::FILE* in, const std::filesystem::path& name);

}  // namespace farm
