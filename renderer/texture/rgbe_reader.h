#pragma once
// Radiance HDR (RGBE) files: a text header, a resolution line, then scanlines either flat (four
// bytes a pixel) or run-length encoded per channel. Every length is checked before it is used.
#include <cstdint>
#include <filesystem>
#include <vector>

#include <glm/vec4.hpp>

namespace farm {

struct RgbeImage {
  int width = 0, height = 0;
  std::vector<glm::vec4> texels;  // linear RGB, alpha 1, rows top to bottom
};

// The pixels of a Radiance file (its first line "#?RADIANCE" or "#?RGBE"). Throws InputError
// naming the file when it is not one, is malformed or truncated, or is larger than `max_side` on a
// side or `max_texels` in all (said from the header, nothing decoded).
RgbeImage read_rgbe(const std::filesystem::path& file, int max_side, std::uint64_t max_texels);

}  // namespace farm
