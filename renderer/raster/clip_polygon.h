#pragma once
// Clipping of a triangle in homogeneous clip space, before the perspective divide, so nothing is
// ever divided by w <= 0. Planes: near and far, and a guard band in x and y wide enough that
// hardly any triangle is cut by it but narrow enough that screen coordinates fit the fixed-point
// rasterizer. Pixels outside the image are excluded later by the bounding box, not by clipping.
#include <array>
#include <cstddef>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace farm::raster {

// The attributes that travel with a vertex through clipping; all are linear in clip space.
struct ClipVertex {
  glm::vec4 clip{0.0f};
  glm::vec3 view_position{0.0f};
  glm::vec3 world_normal{0.0f};
};

// |x|, |y| <= kGuardBand * w after clipping, i.e. NDC within [-kGuardBand, kGuardBand].
inline constexpr float kGuardBand = 4.0f;

// A convex polygon: a triangle clipped by 6 planes has at most 9 vertices.
struct ClippedPolygon {
  std::array<ClipVertex, 9> vertices;
  std::size_t size = 0;
};

// Clips triangle (a, b, c); the result keeps the winding order and may be empty.
ClippedPolygon clip_triangle(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c);

// True when all three vertices lie strictly outside one plane: nothing of the triangle is visible.
bool trivially_outside(const glm::vec4& a, const glm::vec4& b, const glm::vec4& c);

// True when all three vertices are inside every plane: no clipping needed.
bool trivially_inside(const glm::vec4& a, const glm::vec4& b, const glm::vec4& c);

}  // namespace farm::raster
