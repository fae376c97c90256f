#include "renderer/raster/clip_polygon.h"

#include <glm/common.hpp>

namespace farm::raster {
namespace {

// Signed distance to plane i (>= 0 inside), the sides at the guard band.
float plane_distance(const glm::vec4& v, int plane) { return clip_plane_distance(v, plane, kGuardBand); }

// Always interpolates from the inside vertex towards the outside one, so two triangles sharing
// an edge compute bit-identical crossing points and no crack opens between them.
ClipVertex crossing(const ClipVertex& inside, float d_inside, const ClipVertex& outside,
                    float d_outside) {
  const float t = d_inside / (d_inside - d_outside);
  return {glm::mix(inside.clip, outside.clip, t),
          glm::mix(inside.view_position, outside.view_position, t),
          glm::mix(inside.world_normal, outside.world_normal, t)};
}

}  // namespace

std::uint8_t outcode(const glm::vec4& clip) {
  std::uint8_t code = 0;
  for (int p = 0; p < kClipPlaneCount; ++p) {
    if (plane_distance(clip, p) < 0.0f) code = static_cast<std::uint8_t>(code | (1u << p));
  }
  return code;
}

ClippedPolygon clip_triangle(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c) {
  ClippedPolygon poly;
  poly.vertices[0] = a;
  poly.vertices[1] = b;
  poly.vertices[2] = c;
  poly.size = 3;
  for (int plane = 0; plane < kClipPlaneCount && poly.size > 0; ++plane) {
    // Sutherland-Hodgman against one plane.
    ClippedPolygon out;
    for (std::size_t i = 0; i < poly.size; ++i) {
      const ClipVertex& cur = poly.vertices[i];
      const ClipVertex& next = poly.vertices[(i + 1) % poly.size];
      const float d_cur = plane_distance(cur.clip, plane);
      const float d_next = plane_distance(next.clip, plane);
      if (d_cur >= 0.0f) out.vertices[out.size++] = cur;
      if ((d_cur >= 0.0f) != (d_next >= 0.0f)) {
        out.vertices[out.size++] = d_cur >= 0.0f ? crossing(cur, d_cur, next, d_next)
                                                 : crossing(next, d_next, cur, d_cur);
      }
    }
    poly = out;
  }
  if (poly.size < 3) poly.size = 0;
  return poly;
}

}  // namespace farm::raster
