#include "tests/support/image_pairs.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace farm::test {

Image synthetic_reference(int width, int height, std::uint32_t seed) {
  Image image = make_image(width, height, {"R", "G", "B"});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // A few discs of flat colour over a gradient, plus fine texture: edges, flats and detail.
  struct Disc {
    float x, y, r, c[3];
  };
  std::vector<Disc> discs(6);
  for (Disc& d : discs) d = {u(rng) * static_cast<float>(width), u(rng) * static_cast<float>(height),
                             (0.1f + 0.2f * u(rng)) * static_cast<float>(std::min(width, height)),
                             {u(rng), u(rng), u(rng)}};
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float fx = static_cast<float>(x) / static_cast<float>(width), fy = static_cast<float>(y) / static_cast<float>(height);
      float c[3] = {0.2f + 0.6f * fx, 0.3f + 0.5f * fy, 0.5f + 0.3f * std::sin(6.0f * fx + 3.0f * fy)};
      for (const Disc& d : discs) {
        const float dx = static_cast<float>(x) - d.x, dy = static_cast<float>(y) - d.y;
        if (dx * dx + dy * dy < d.r * d.r) std::copy(d.c, d.c + 3, c);
      }
      const float texture = 0.05f * std::sin(static_cast<float>(x) * 1.7f) * std::cos(static_cast<float>(y) * 2.3f);
      for (int ch = 0; ch < 3; ++ch) image.at(x, y, ch) = std::clamp(c[ch] + texture, 0.0f, 1.0f);
    }
  return image;
}

Image make_variant(const Image& reference, const Variant& v, bool clamp) {
  Image out = reference;
  std::mt19937 rng(v.seed);
  std::normal_distribution<double> noise(0.0, v.noise > 0.0 ? v.noise : 1.0);
  std::uniform_int_distribution<int> px(0, reference.width - 1), py(0, reference.height - 1);
  const int channels = static_cast<int>(reference.channel_count());
  for (int y = 0; y < reference.height; ++y)
    for (int x = 0; x < reference.width; ++x)
      for (int c = 0; c < channels; ++c) {
        const int from_x = std::clamp(x - v.shift_x, 0, reference.width - 1);
        double value = reference.at(from_x, y, c) * v.gain + v.offset;
        if (v.noise > 0.0) value += noise(rng);
        if (clamp) value = std::clamp(value, 0.0, 1.0);
        out.at(x, y, c) = static_cast<float>(value);
      }
  for (int i = 0; i < v.hot_pixels; ++i) {
    const int x = px(rng), y = py(rng);
    for (int c = 0; c < channels; ++c) out.at(x, y, c) = 1.0f;
  }
  return out;
}

}  // namespace farm::test
