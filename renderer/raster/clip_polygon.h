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

// The clip planes, in outcode bit order: near, far, then the sides x and y at +-band * w.
inline constexpr int kClipPlaneCount = 6;

// Signed distance of clip-space point v inside plane `plane` (>= 0 inside): near z >= -w, far
// z <= w, and |x|, |y| <= band * w (the guard band when clipping; 1, the image's edges, when
// culling whole meshes, view_culling.h). One definition, in float or double, for both.
template <typename Vec4, typename Scalar>
Scalar clip_plane_distance(const Vec4& v, int plane, Scalar band) {
  switch (plane) {
    case 0: return v.z + v.w;
    case 1: return v.w - v.z;
    case 2: return band * v.w - v.x;
    case 3: return band * v.w + v.x;
    case 4: return band * v.w - v.y;
    default: return band * v.w + v.y;
  }
}

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
