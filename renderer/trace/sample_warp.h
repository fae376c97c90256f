#pragma once
// Uniform numbers warped onto what the samplers need (docs/architecture.md, 8.1): a
// cosine-weighted direction, a uniform point on a triangle, and the orthonormal frame around a
// normal that carries local directions to the world. One copy each, shared by the path tracer's
// BSDFs and lights and by the emitter-facing check (`farm info`), so that they cannot drift apart.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "renderer/util/unit_circle.h"

namespace farm {

// A cosine-weighted direction about +z (Malley's method: a uniform point on the unit disc lifted
// onto the hemisphere). The angle from unit_circle_point: the same bits on every machine.
inline glm::vec3 cosine_hemisphere(float u1, float u2) {
  const float r = std::sqrt(u1);
  const CosSin phi = unit_circle_point(u2);
  return {r * phi.cos, r * phi.sin, std::sqrt(std::max(0.0f, 1.0f - u1))};
}

// A uniform point on a triangle p0 + b1 e1 + b2 e2, as its weights (b1, b2): the unit square
// folded onto the triangle by a square root (no rejection, so one pair of numbers is one point).
inline glm::vec2 uniform_triangle_weights(float u1, float u2) {
  const float s = std::sqrt(u1);
  return {1.0f - s, u2 * s};
}

// An orthonormal frame (t, b, n) around a unit normal, without a branch or a division by a small
// number (Duff et al. 2017, "Building an orthonormal basis, revisited").
struct ShadingFrame {
  glm::vec3 t, b, n;
  explicit ShadingFrame(const glm::vec3& normal) : n(normal) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = {1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
    b = {c, sign + n.y * n.y * a, -n.y};
  }
  glm::vec3 to_local(const glm::vec3& v) const { return {glm::dot(v, t), glm::dot(v, b), glm::dot(v, n)}; }
  glm::vec3 to_world(const glm::vec3& v) const { return v.x * t + v.y * b + v.z * n; }
};

}  // namespace farm
