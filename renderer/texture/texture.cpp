#include "renderer/texture/texture.h"

#include <algorithm>
#include <cmath>
#include <glm/common.hpp>
#include <stdexcept>
#include <utility>

namespace farm {
namespace {

// Texel index `i` of a side `n` long, wrapped into [0, n).
int wrap_index(int i, int n, TextureWrap wrap) {
  // Nearly every index is inside already, and every mode keeps those: no integer division
  // (Repeat's two per index, four indices a bilinear lookup, were most of an environment map's
  // lookup time).
  if (static_cast<unsigned>(i) < static_cast<unsigned>(n)) return i;
  switch (wrap) {
    case TextureWrap::ClampToEdge: return std::clamp(i, 0, n - 1);
    case TextureWrap::MirroredRepeat: {
      const int period = 2 * n;
      const int m = ((i % period) + period) % period;
      return m < n ? m : period - 1 - m;
    }
    case TextureWrap::Repeat: break;
  }
  return ((i % n) + n) % n;
}

// A coordinate in texels, kept to a range where the float-to-int conversion is defined (wrapping
// makes every value beyond it equivalent to one inside, up to the precision a float has there).
float finite_coordinate(float texels) {
  if (!std::isfinite(texels)) return 0.0f;
  constexpr float kLimit = 1 << 24;
  return std::clamp(texels, -kLimit, kLimit);
}

}  // namespace

Texture::Texture(int width, int height, std::vector<glm::vec4> texels) : width_(width), height_(height) {
  if (width <= 0 || height <= 0 ||
      texels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw std::invalid_argument("Texture: texels do not match its size");
  }
  levels_.push_back(Level{width, height, std::move(texels)});
  // Each level a 2x2 box average of the one above; an odd side reads its last texel twice.
  while (levels_.back().width > 1 || levels_.back().height > 1) {
    const Level& above = levels_.back();
    Level next;
    next.width = std::max(1, above.width / 2);
    next.height = std::max(1, above.height / 2);
    next.texels.resize(static_cast<std::size_t>(next.width) * static_cast<std::size_t>(next.height));
    const auto at = [&](int x, int y) {
      return above.texels[static_cast<std::size_t>(std::min(y, above.height - 1)) * static_cast<std::size_t>(above.width) +
                          static_cast<std::size_t>(std::min(x, above.width - 1))];
    };
    for (int y = 0; y < next.height; ++y)
      for (int x = 0; x < next.width; ++x)
        next.texels[static_cast<std::size_t>(y) * static_cast<std::size_t>(next.width) + static_cast<std::size_t>(x)] =
            0.25f * (at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) + at(2 * x + 1, 2 * y + 1));
    levels_.push_back(std::move(next));
  }
}

int Texture::level_width(int level) const { return levels_[static_cast<std::size_t>(level)].width; }
int Texture::level_height(int level) const { return levels_[static_cast<std::size_t>(level)].height; }

const glm::vec4& Texture::texel(int level, int x, int y) const {
  const Level& l = levels_[static_cast<std::size_t>(level)];
  return l.texels[static_cast<std::size_t>(y) * static_cast<std::size_t>(l.width) + static_cast<std::size_t>(x)];
}

glm::vec4 Texture::sample(glm::vec2 uv, const TextureSampler& sampler, float footprint) const {
  const auto read = [&](int level, TextureFilter filter) {
    const Level& l = levels_[static_cast<std::size_t>(level)];
    // A texel's row start and column, wrapped once each (a bilinear lookup shares two of each).
    const auto row = [&](int y) {
      return static_cast<std::size_t>(wrap_index(y, l.height, sampler.wrap_v)) * static_cast<std::size_t>(l.width);
    };
    const auto column = [&](int x) { return static_cast<std::size_t>(wrap_index(x, l.width, sampler.wrap_u)); };
    if (filter == TextureFilter::Nearest) {
      return l.texels[row(static_cast<int>(std::floor(finite_coordinate(uv.y * static_cast<float>(l.height))))) +
                      column(static_cast<int>(std::floor(finite_coordinate(uv.x * static_cast<float>(l.width)))))];
    }
    // Texel centres sit at (i + 0.5) / side.
    const float x = finite_coordinate(uv.x * static_cast<float>(l.width) - 0.5f);
    const float y = finite_coordinate(uv.y * static_cast<float>(l.height) - 0.5f);
    const float fx0 = std::floor(x), fy0 = std::floor(y);
    const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
    const float fx = x - fx0, fy = y - fy0;
    const std::size_t r0 = row(y0), r1 = row(y0 + 1), c0 = column(x0), c1 = column(x0 + 1);
    return (1.0f - fy) * ((1.0f - fx) * l.texels[r0 + c0] + fx * l.texels[r0 + c1]) +
           fy * ((1.0f - fx) * l.texels[r1 + c0] + fx * l.texels[r1 + c1]);
  };
  // Kept below the level count: a huge footprint overflows the product to inf, whose conversion
  // to int below would be undefined (and index far outside levels_).
  const float lod = footprint > 0.0f && std::isfinite(footprint)
                        ? std::min(std::log2(footprint * static_cast<float>(std::max(width_, height_))),
                                   static_cast<float>(levels()))
                        : 0.0f;
  if (!(lod > 0.0f)) return read(0, sampler.magnify);
  if (!sampler.mipmaps) return read(0, sampler.minify);
  const int last = levels() - 1;
  if (sampler.minify == TextureFilter::Nearest) {
    return read(std::min(last, static_cast<int>(std::lround(lod))), TextureFilter::Nearest);
  }
  const float base = std::floor(lod);
  const int fine = std::min(last, static_cast<int>(base)), coarse = std::min(last, fine + 1);
  const float t = lod - base;
  if (fine == coarse) return read(fine, TextureFilter::Linear);
  return (1.0f - t) * read(fine, TextureFilter::Linear) + t * read(coarse, TextureFilter::Linear);
}

std::size_t Texture::memory_bytes() const {
  std::size_t bytes = 0;
  for (const Level& l : levels_) bytes += l.texels.size() * sizeof(glm::vec4);
  return bytes;
}

glm::mat3 uv_transform(glm::vec2 offset, float rotation, glm::vec2 scale) {
  // KHR_texture_transform's T * R * S in the spec's row-major notation; glm takes columns.
  const float c = std::cos(rotation), s = std::sin(rotation);
  const glm::mat3 translation(1, 0, 0, 0, 1, 0, offset.x, offset.y, 1);
  const glm::mat3 rotate(c, -s, 0, s, c, 0, 0, 0, 1);
  const glm::mat3 scaling(scale.x, 0, 0, 0, scale.y, 0, 0, 0, 1);
  return translation * rotate * scaling;
}

}  // namespace farm
