#pragma once
// Clipping of a triangle in homogeneous clip space, before the perspective divide, so nothing is
// ever divided by w <= 0. Planes: near and far, and a guard band in x and y wide enough that
// hardly any triangle is cut by it but narrow enough that screen coordinates fit the fixed-point
// rasterizer. Pixels outside the image are excluded later by the bounding box, not by clipping.
#include <array>
#include <cstddef>
#include <cstdint>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace farm::raster {

// The attributes that travel with a vertex through clipping; all are linear in clip space.
// Trivial (no member initializers), so per-frame arrays of them can start uninitialized.
struct ClipVertex {
  glm::vec4 clip;
  glm::vec3 view_position;
  glm::vec3 world_normal;
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

// One bit per clip plane that `clip` lies outside of. A triangle whose vertices share a bit is
// invisible (all outside one plane); one whose vertices have no bits needs no clipping.
std::uint8_t outcode(const glm::vec4& clip);

}  // namespace farm::raster
