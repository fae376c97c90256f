#pragma once
// The pinhole camera (docs/architecture.md, "Conventions"): looks from `position` at `target`; view space looks down -Z.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <limits>
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
  // has unit length along forward(), so the hit's t is the depth along the viewing axis. An
  // engine tracing many asks CameraRays, which works out the image's part once.
  Ray primary_ray(float px, float py, int width, int height) const;

  // How tall one pixel of an image `height` pixels tall is at unit depth: a pixel's footprint
  // grows as this times the depth (texture filtering).
  float pixel_size_at_unit_depth(int height) const;
};

// Camera::primary_ray for one image size, with what does not depend on the pixel (the camera's
// frame, two square roots, the tangent of the field of view) worked out once instead of per ray:
// the same operations on the same values, so the same bits as primary_ray.
class CameraRays {
 public:
  CameraRays(const Camera& camera, int width, int height);
  // Inline: the path tracer asks one per sample.
  Ray ray(float px, float py) const {
    const float ndc_x = 2.0f * px / width_ - 1.0f;
    const float ndc_y = 1.0f - 2.0f * py / height_;
    const glm::vec3 d = forward_ + (ndc_x * tan_half_ * aspect_) * right_ + (ndc_y * tan_half_) * up_;
    return Ray{position_, d, 0.0f, std::numeric_limits<float>::infinity()};
  }

 private:
  glm::vec3 position_, forward_, right_, up_;
  float tan_half_, aspect_, width_, height_;
};

}  // namespace farm
