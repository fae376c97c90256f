#pragma once
// The pinhole camera (docs/architecture.md, "Conventions"): looks from `position` at `target`; view space looks down -Z.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <optional>

#include "renderer/geometry/ray.h"

namespace farm {

struct Camera {
  glm::vec3 position{5.0f, 5.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fov_y_degrees = 45.0f;
  float near = 0.1f;
  float far = 10.0f;
  std::optional<float> aspect;  // width / height of the image unless given

  float aspect_for(int width, int height) const {
    return aspect ? *aspect : static_cast<float>(width) / static_cast<float>(height);
  }
  glm::mat4 view_matrix() const;                    // world -> view (rigid)
  glm::mat4 projection_matrix(float aspect_ratio) const;  // view -> clip, OpenGL depth range
  glm::vec3 forward() const;                        // unit viewing axis in world space

  // Ray through image point (px, py) in pixels (y down; a pixel centre is x + 0.5). Its direction
  // has unit length along forward(), so the hit's t is the depth along the viewing axis.
  Ray primary_ray(float px, float py, int width, int height) const;

  // How tall one pixel of an image `height` pixels tall is at unit depth: a pixel's footprint
  // grows as this times the depth (texture filtering).
  float pixel_size_at_unit_depth(int height) const;
};

}  // namespace farm
