#include "renderer/scene/transform.h"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <glm/trigonometric.hpp>

namespace farm {

glm::mat4 ObjectTransform::matrix() const {
  glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
  if (rotate_degrees != 0.0f) {
    m = glm::rotate(m, glm::radians(rotate_degrees), glm::normalize(rotate_axis));
  }
  return glm::scale(m, scale);
}

glm::mat3 normal_matrix(const glm::mat4& model_to_world) {
  return glm::transpose(glm::inverse(glm::mat3(model_to_world)));
}

}  // namespace farm
