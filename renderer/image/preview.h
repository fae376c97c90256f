#pragma once
// 8-bit previews (PNG or JPEG, chosen by extension) of a linear film: RGB clamped to [0, 1] and
// sRGB-encoded.
#include <cstdint>
#include <filesystem>

#include "renderer/image/rgb8_image.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

float linear_to_srgb(float linear);      // the sRGB transfer function, input clamped to [0, 1]
std::uint8_t to_srgb8(float linear);        // rounded to 8 bits: what previews hold

// The film's RGB as a preview holds it: every channel through to_srgb8, rows top to bottom.
Rgb8Image to_srgb8_image(const TileBuffer& image);

// Writes to a temporary file beside `file` and renames it into place. Errors name `file`.
void write_preview(const TileBuffer& image, const std::filesystem::path& file);

// True for the extensions write_preview knows, in any case: .png; .jpg .jpeg .jpe .jif .jfif .jfi
// (checked before a long render starts).
bool preview_format_supported(const std::filesystem::path& file);

}  // namespace farm
