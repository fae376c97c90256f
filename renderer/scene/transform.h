#pragma once
// An object's placement as a job states it: scale, then rotate about an axis, then translate.
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace farm {

struct ObjectTransform {
  glm::vec3 translate{0.0f};
  glm::vec3 rotate_axis{0.0f, 1.0f, 0.0f};
  float rotate_degrees = 0.0f;
  glm::vec3 scale{1.0f};

  glm::mat4 matrix() const;  // T * R * S
};

// Normals transform by the inverse transpose of the linear part, so they stay perpendicular to
// surfaces under non-uniform scale.
glm::mat3 normal_matrix(const glm::mat4& model_to_world);

}  // namespace farm
