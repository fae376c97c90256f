#include "renderer/scene/camera.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/trigonometric.hpp>

namespace farm {

glm::mat4 Camera::view_matrix() const { return glm::lookAtRH(position, target, up); }

glm::mat4 Camera::projection_matrix(float aspect_ratio) const {
  return glm::perspectiveRH_NO(glm::radians(fov_y_degrees), aspect_ratio, near, far);
}

glm::vec3 Camera::forward() const { return glm::normalize(target - position); }

Ray Camera::primary_ray(float px, float py, int width, int height) const {
  const glm::vec3 f = forward();
  const glm::vec3 right = glm::normalize(glm::cross(f, up));
  const glm::vec3 true_up = glm::cross(right, f);
  const float tan_half = std::tan(glm::radians(fov_y_degrees) * 0.5f);
  const float ndc_x = 2.0f * px / static_cast<float>(width) - 1.0f;
  const float ndc_y = 1.0f - 2.0f * py / static_cast<float>(height);
  const glm::vec3 d = f + (ndc_x * tan_half * aspect_for(width, height)) * right +
                      (ndc_y * tan_half) * true_up;
  return Ray{position, d, 0.0f, std::numeric_limits<float>::infinity()};
}

float Camera::pixel_size_at_unit_depth(int height) const {
  return 2.0f * std::tan(glm::radians(fov_y_degrees) * 0.5f) / static_cast<float>(height);
}

}  // namespace farm
