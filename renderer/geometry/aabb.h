#pragma once
#include <glm/common.hpp>
#include <glm/vec3.hpp>
#include <limits>

namespace farm {

// Axis-aligned box; an empty box has min > max so that growing it by any point is correct.
struct AABB {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};

  bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
  void grow(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void grow(const AABB& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  glm::vec3 extent() const { return max - min; }
  glm::vec3 center() const { return 0.5f * (min + max); }
};

}  // namespace farm
