#pragma once
#include <glm/vec3.hpp>

namespace farm {

// A delta light. Point lights fall off as intensity / r^2; directional lights (from model files)
// deliver `intensity` as irradiance from one direction, with no falloff.
struct Light {
  enum class Kind { Point, Directional };
  Kind kind = Kind::Point;
  glm::vec3 position{0.0f};
  glm::vec3 direction{0.0f, -1.0f, 0.0f};  // direction the light travels (directional only)
  glm::vec3 intensity{10.0f};
};

}  // namespace farm
