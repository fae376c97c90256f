#include "renderer/texture/height_map.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <vector>

namespace farm {
namespace {

// The texel index `i` stands for on a side of `n` texels, as the wrap mode reads outside it.
int wrapped(int i, int n, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::Repeat: return ((i % n) + n) % n;
    case TextureWrap::ClampToEdge: return std::clamp(i, 0, n - 1);
    case TextureWrap::MirroredRepeat: {
      const int period = 2 * n;
      const int k = ((i % period) + period) % period;
      return k < n ? k : period - 1 - k;
    }
  }
  return std::clamp(i, 0, n - 1);
}

}  // namespace

std::shared_ptr<const Texture> normal_map_from_height(const Texture& height, float scale, TextureWrap wrap_u,
                                                      TextureWrap wrap_v) {
  const int w = height.width(), h = height.height();
  const auto at = [&](int x, int y) {
    const glm::vec4& t = height.texel(0, wrapped(x, w, wrap_u), wrapped(y, h, wrap_v));
    return 0.2126f * t.x + 0.7152f * t.y + 0.0722f * t.z;  // Rec. 709 luminance
  };
  std::vector<glm::vec4> normals(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      // Height per uv unit: the difference across two texels, over their 2 / size.
      const float dh_du = scale * (at(x + 1, y) - at(x - 1, y)) * 0.5f * static_cast<float>(w);
      const float dh_dv = scale * (at(x, y + 1) - at(x, y - 1)) * 0.5f * static_cast<float>(h);
      // The surface z = h(u, y_up) with y_up = -v has the normal (-dh/du, -dh/dy_up, 1).
      const glm::vec3 n = glm::normalize(glm::vec3(-dh_du, dh_dv, 1.0f));
      normals[static_cast<std::size_t>(y) * w + x] = glm::vec4(0.5f * n + 0.5f, 1.0f);
    }
  return std::make_shared<const Texture>(w, h, std::move(normals));
}

}  // namespace farm
