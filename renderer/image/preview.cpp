#include "renderer/image/preview.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "renderer/image/output_file.h"
#include "renderer/image/preview_writer.h"

namespace farm {

float linear_to_srgb(float linear) {
  if (std::isnan(linear)) return 0.0f;  // NaN shows as black, not as garbage
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

std::uint8_t to_srgb8(float linear) {
  return static_cast<std::uint8_t>(std::lround(linear_to_srgb(linear) * 255.0f));
}

bool preview_format_supported(const std::filesystem::path& file) {
  return preview_writer().can_write(file.c_str()) != 0;
}

void write_preview(const TileBuffer& image, const std::filesystem::path& file) {
  const Rect& r = image.rect();
  if (r.empty()) throw std::invalid_argument(fmt::format("{}: cannot write an empty image", file.string()));
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(r.width()) *
                                   static_cast<std::size_t>(r.height()) * 3);
  std::size_t i = 0;
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x) {
      const glm::vec4& c = image.rgba(x, y);
      pixels[i++] = to_srgb8(c.x);
      pixels[i++] = to_srgb8(c.y);
      pixels[i++] = to_srgb8(c.z);
    }
  }
  const PreviewWriter& writer = preview_writer();
  write_file_atomically(file, [&](const std::filesystem::path& temp) {
    char error[512] = "";
    if (writer.write_rgb8(temp.c_str(), r.width(), r.height(), pixels.data(), error, sizeof error) == 0) {
      throw std::runtime_error(fmt::format("{}: cannot write preview: {}", file.string(), error));
    }
  });
}

}  // namespace farm
