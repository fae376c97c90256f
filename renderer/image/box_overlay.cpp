#include "renderer/image/box_overlay.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/common.hpp>

namespace farm {

BoxOverlay::BoxOverlay(TileBuffer& image, const Camera& camera) : image_(image), camera_(camera) {
  view_ = camera.view_matrix();
  projection_ = camera.projection_matrix(camera.aspect_for(image.rect().width(), image.rect().height()));
}

glm::vec3 BoxOverlay::level_color(int level) {
  static const std::array<glm::vec3, 6> palette = {
      glm::vec3(1.0f, 0.2f, 0.2f), glm::vec3(1.0f, 0.8f, 0.1f), glm::vec3(0.2f, 1.0f, 0.3f),
      glm::vec3(0.2f, 0.8f, 1.0f), glm::vec3(0.5f, 0.4f, 1.0f), glm::vec3(1.0f, 0.4f, 0.9f)};
  return palette[static_cast<std::size_t>(level) % palette.size()];
}

void BoxOverlay::draw_box(const AABB& box, const glm::mat4& to_world, const glm::vec3& color) {
  std::array<glm::vec3, 8> corner;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 c{(i & 1) ? box.max.x : box.min.x, (i & 2) ? box.max.y : box.min.y,
                      (i & 4) ? box.max.z : box.min.z};
    corner[static_cast<std::size_t>(i)] = glm::vec3(to_world * glm::vec4(c, 1.0f));
  }
  // Corners i and j share an edge when their indices differ in exactly one bit.
  for (int i = 0; i < 8; ++i)
    for (int bit : {1, 2, 4})
      if (!(i & bit)) draw_segment(corner[static_cast<std::size_t>(i)], corner[static_cast<std::size_t>(i | bit)], color);
}

void BoxOverlay::draw_segment(glm::vec3 a_world, glm::vec3 b_world, const glm::vec3& color) {
  // Clip in view space against the near plane so nothing behind the camera is projected.
  glm::vec3 a = glm::vec3(view_ * glm::vec4(a_world, 1.0f)), b = glm::vec3(view_ * glm::vec4(b_world, 1.0f));
  const float near_z = -camera_.near;
  if (a.z > near_z && b.z > near_z) return;
  if (a.z > near_z) a = glm::mix(a, b, (near_z - a.z) / (b.z - a.z));
  if (b.z > near_z) b = glm::mix(b, a, (near_z - b.z) / (a.z - b.z));

  const Rect& r = image_.rect();
  const auto to_pixel = [&](const glm::vec3& v) {
    const glm::vec4 clip = projection_ * glm::vec4(v, 1.0f);
    return glm::vec2((clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(r.width()),
                     (0.5f - clip.y / clip.w * 0.5f) * static_cast<float>(r.height()));
  };
  const glm::vec2 pa = to_pixel(a), pb = to_pixel(b);
  // A simple DDA, one step per pixel along the longer axis; only pixels in the image are set.
  const float steps = std::ceil(std::max(std::fabs(pb.x - pa.x), std::fabs(pb.y - pa.y)));
  if (!(steps < 1e6f)) return;  // degenerate projection
  for (int i = 0; i <= static_cast<int>(steps); ++i) {
    const glm::vec2 p = steps > 0.0f ? glm::mix(pa, pb, static_cast<float>(i) / steps) : pa;
    const int x = static_cast<int>(std::floor(p.x)), y = static_cast<int>(std::floor(p.y));
    if (r.contains(x, y)) image_.rgba(x, y) = glm::vec4(color, 1.0f);
  }
}

}  // namespace farm
