#pragma once
// A decoded texture: linear RGBA floats with its mip chain, and how a material samples it
// (docs/architecture.md, "Textures"). Texture coordinates follow glTF: u to the right, v down,
// (0, 0) the top-left corner of the image's first row, texel (i, j) covering
// [i / width, (i + 1) / width] x [j / height, (j + 1) / height]. Loaders of formats whose v points
// up (OBJ, COLLADA, PLY) flip it once, at load.
#include <cstddef>
#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec4.hpp>
#include <memory>
#include <vector>

namespace farm {

// glTF's sampler wrap modes, for coordinates outside [0, 1].
enum class TextureWrap { Repeat, ClampToEdge, MirroredRepeat };
// Nearest texel or bilinear between four; minification with Linear also blends two mip levels.
enum class TextureFilter { Nearest, Linear };

struct TextureSampler {
  TextureWrap wrap_u = TextureWrap::Repeat;
  TextureWrap wrap_v = TextureWrap::Repeat;
  TextureFilter magnify = TextureFilter::Linear;
  TextureFilter minify = TextureFilter::Linear;
  bool mipmaps = true;  // false: minification reads level 0 only
};

class Texture {
 public:
  // `texels`: width * height linear RGBA values, rows top to bottom. Builds the mip chain (each
  // level a 2x2 box average of the one above, odd sides clamped) down to 1x1.
  Texture(int width, int height, std::vector<glm::vec4> texels);

  int width() const { return width_; }
  int height() const { return height_; }
  int levels() const { return static_cast<int>(levels_.size()); }
  int level_width(int level) const;
  int level_height(int level) const;
  const glm::vec4& texel(int level, int x, int y) const;

  // The filtered value at `uv`. `footprint`: how much of the texture one pixel's footprint spans,
  // in uv units (the larger of |d uv / dx| and |d uv / dy|); 0 samples level 0 only. Deterministic:
  // the same arguments give the same bits on every thread and machine.
  glm::vec4 sample(glm::vec2 uv, const TextureSampler& sampler, float footprint = 0.0f) const;

  // What the texels of every level hold, in bytes.
  std::size_t memory_bytes() const;

 private:
  struct Level {
    int width = 0, height = 0;
    std::vector<glm::vec4> texels;
  };
  int width_ = 0, height_ = 0;
  std::vector<Level> levels_;
};

// KHR_texture_transform as one matrix: uv' = (T * R * S) (u, v, 1); identity when absent.
glm::mat3 uv_transform(glm::vec2 offset, float rotation, glm::vec2 scale);

}  // namespace farm
