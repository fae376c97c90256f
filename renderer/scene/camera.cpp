#include "renderer/scene/camera.h"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/trigonometric.hpp>

namespace farm {

glm::mat4 Camera::view_matrix() const { return glm::lookAtRH(position, target, up); }

glm::mat4 Camera::projection_matrix(float aspect_ratio) const {
  return glm::perspectiveRH_NO(glm::radians(fov_y_degrees), aspect_ratio, near, far);
}

glm::vec3 Camera::forward() const { return glm::normalize(target - position); }

}  // namespace farm
