#pragma once
#include <glm/vec3.hpp>
#include <limits>

namespace farm {

struct Ray {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // not necessarily unit: t is in units of |direction|
  float t_min = 0.0f;
  float t_max = std::numeric_limits<float>::infinity();

  glm::vec3 at(float t) const { return origin + t * direction; }
};

}  // namespace farm
