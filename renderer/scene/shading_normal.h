#pragma once
// Which way a shading normal faces the viewer (docs/architecture.md §8.4). A normal map may bend
// the normal so far that a viewer at a grazing angle lies below it: turned around (the two-sided
// rule for plain normals) it would point into the surface, and everything above the surface would
// lie behind it, a black speck. Reflected about the geometric normal instead, it keeps its tilt
// and faces the viewer: what Mitsuba's normalmap adapter over a two-sided BSDF amounts to.
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace farm {

// `bent` (unit) on the side of the surface `to_eye` looks from, `surface` (unit) the normal before
// the map bent it (the geometric one, or the interpolated one in the rasterizer). The result
// faces `to_eye` whenever `surface` turned to the viewer does.
inline glm::vec3 bent_normal_facing(const glm::vec3& bent, const glm::vec3& surface, const glm::vec3& to_eye) {
  const glm::vec3 g = glm::dot(surface, to_eye) >= 0.0f ? surface : -surface;
  glm::vec3 n = glm::dot(bent, g) >= 0.0f ? bent : -bent;
  if (glm::dot(n, to_eye) < 0.0f) n = 2.0f * glm::dot(n, g) * g - n;
  return n;
}

}  // namespace farm
