#pragma once
// Where a secondary ray (bounce or shadow) starts: off the surface along the geometric normal,
// on the side the ray leaves by, far enough to clear float error at this distance from the
// origin, so it cannot hit the surface it starts on.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace farm {

inline glm::vec3 offset_ray_origin(const glm::vec3& p, const glm::vec3& geometric_normal,
                                   const glm::vec3& direction) {
  const float scale = 1e-4f * (1.0f + std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}));
  return p + (glm::dot(direction, geometric_normal) > 0.0f ? scale : -scale) * geometric_normal;
}

}  // namespace farm
