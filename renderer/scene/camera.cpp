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
  return CameraRays(*this, width, height).ray(px, py);
}

CameraRays::CameraRays(const Camera& camera, int width, int height)
    : position_(camera.position),
      forward_(camera.forward()),
      right_(glm::normalize(glm::cross(forward_, camera.up))),
      up_(glm::cross(right_, forward_)),
      tan_half_(std::tan(glm::radians(camera.fov_y_degrees) * 0.5f)),
      aspect_(camera.aspect_for(width, height)),
      width_(static_cast<float>(width)),
      height_(static_cast<float>(height)) {}

float Camera::pixel_size_at_unit_depth(int height) const {
  return 2.0f * std::tan(glm::radians(fov_y_degrees) * 0.5f) / static_cast<float>(height);
}

}  // namespace farm
