#include "renderer/job/job_checks.h"

#include <fmt/format.h>

#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <string>

namespace farm {

namespace {

std::string vec_text(const glm::vec3& p) { return fmt::format("({}, {}, {})", p.x, p.y, p.z); }

}  // namespace

glm::vec3 unit_axis(const glm::vec3& axis, const JsonPlace& at) {
  const glm::dvec3 d(axis);
  const double len = std::sqrt(glm::dot(d, d));
  if (!(len > 0.0)) at.fail("expected a non-zero axis, got (0, 0, 0)");
  return glm::vec3(d / len);
}

void check_scale(const glm::vec3& scale, const JsonPlace& at) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (scale[static_cast<glm::length_t>(i)] == 0.0f) at.index(i).fail("expected a non-zero scale factor, got 0");
  }
}

void check_camera(const Camera& cam, const CameraKeys& given, const JsonPlace& camera) {
  if (!(cam.far > cam.near)) {
    if (given.far || !given.near) {
      (given.far ? camera.key("far") : camera).fail(fmt::format("expected far > near ({}), got {}", cam.near, cam.far));
    }
    camera.key("near").fail(fmt::format("expected near < far ({}, the default), got {}", cam.far, cam.near));
  }

  // The view basis is built in float (glm::lookAt); refuse what would make it degenerate.
  const glm::vec3 view = cam.target - cam.position;
  const float view_len2 = glm::dot(view, view);
  if (view == glm::vec3(0.0f)) {
    camera.fail(fmt::format("position and target are the same point {}", vec_text(cam.position)));
  }
  if (!std::isfinite(view_len2) || view_len2 < std::numeric_limits<float>::min()) {
    camera.fail(fmt::format("position {} and target {} are too close or too far apart to aim the camera",
                            vec_text(cam.position), vec_text(cam.target)));
  }
  const JsonPlace up = camera.key("up");
  if (cam.up == glm::vec3(0.0f)) up.fail("expected a non-zero up vector, got (0, 0, 0)");
  const glm::dvec3 f = glm::normalize(glm::dvec3(view));
  const glm::dvec3 u = glm::normalize(glm::dvec3(cam.up));
  if (glm::length(glm::cross(f, u)) < 1e-6) {
    up.fail(fmt::format("{}up {} is parallel to the viewing direction (target - position)",
                        given.up ? "" : "the default ", vec_text(cam.up)));
  }
  const glm::vec3 side = glm::cross(glm::normalize(view), cam.up);
  const float side_len2 = glm::dot(side, side);
  if (!std::isfinite(side_len2) || side_len2 < std::numeric_limits<float>::min()) {
    up.fail(fmt::format("up {} is too short or too long to orient the camera", vec_text(cam.up)));
  }
}

}  // namespace farm
