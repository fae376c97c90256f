#pragma once
// PNG files for previews, speed before size (png_strips.h: written here, not through libpng).
#include <cstdio>
#include <filesystem>

#include "renderer/image/rgb8_image.h"

namespace farm {

// Writes `image` as an 8-bit RGB PNG marked sRGB, at zlib level 1, to `out`. Throws
// std::runtime_error naming `name` (what the caller knows `out` as) for an image without pixels,
// std::system_error with its errno when a write fails.
void write_png(const Rgb8Image& image, std::FILE* out, const std::filesystem::path& name);
// The same, its rows taken one by one (an exception from rows.row stops the file and is rethrown).
void write_png(const Rgb8Rows& rows, std::FILE* out, const std::filesystem::path& name);

}  // namespace farm
