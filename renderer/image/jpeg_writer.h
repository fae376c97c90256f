#pragma once
// JPEG files through libjpeg (libjpeg-turbo on Debian), for previews.
#include <cstdio>
#include <filesystem>

#include "renderer/image/rgb8_image.h"

namespace farm {

// Writes `image` as a baseline JPEG, quality 98 with 4:2:0 chroma (what previews had through
// OpenImageIO), to `out`. Throws std::runtime_error naming `name` on any libjpeg error.
void write_jpeg(const Rgb8Image& image, std::FILE* out, const std::filesystem::path& name);
// The same, its rows taken one by one (an exception from rows.row stops the file and is rethrown).
void write_jpeg(const Rgb8Rows& rows, std::FILE* out, const std::filesystem::path& name);

}  // namespace farm
