#pragma once
// Texture files decoded into Textures: PNG (8 and 16 bit), JPEG, OpenEXR and Radiance HDR, by
// their contents, not their extension. Every size is checked from the header before a pixel is
// decoded (docs/architecture.md, "Textures").
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "renderer/texture/texture.h"

namespace farm {

// How a file's stored values are read. Colour (base colour, emissive): 8- and 16-bit values are
// sRGB-encoded and decoded to linear; alpha stays linear. Data (metal-roughness, normals,
// occlusion): values as stored. EXR and HDR hold linear values either way.
enum class TextureColourSpace { Srgb, Linear };

// A texture may be at most 16384 on a side and hold at most 2^26 texels (8192 x 8192: 1 GiB as
// RGBA floats, 1.33 GiB with its mips).
inline constexpr int kMaxTextureSide = 16384;
inline constexpr std::uint64_t kMaxTextureTexels = std::uint64_t{1} << 26;

// Decodes `file` into linear RGBA (grey copied to R G B; alpha 1 where the file has none).
// Throws InputError naming the file: missing, not a PNG/JPEG/EXR/HDR, malformed, or larger than
// the limits above (said from the header, nothing decoded).
std::shared_ptr<const Texture> load_texture_file(const std::filesystem::path& file, TextureColourSpace space);

// The same for a PNG or JPEG held in memory (an image embedded in a model file), `name` naming it
// in messages.
std::shared_ptr<const Texture> load_texture_bytes(std::span<const unsigned char> encoded, const std::string& name,
                                                  TextureColourSpace space);

}  // namespace farm
