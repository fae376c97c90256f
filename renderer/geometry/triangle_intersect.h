#pragma once
// Möller-Trumbore ray/triangle intersection: solves origin + t*d = (1-u-v)*a + u*b + v*c by
// Cramer's rule without precomputing the triangle's plane.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/geometric.hpp>
#include <optional>

#include "renderer/geometry/ray.h"

namespace farm {

// One ray/triangle hit; MeshAccel (mesh_accel.h) reports the same type with `triangle` set.
struct TriangleHit {
  float t = 0.0f;            // in units of the ray's direction (unchanged by an affine map)
  float u = 0.0f, v = 0.0f;  // barycentric weights of corners 1 and 2 (vertices b and c)
  std::uint32_t triangle = 0;  // index into ModelTriangles; intersect_triangle leaves it 0
};

// Hits with t in (max(ray.t_min, t_epsilon), ray.t_max); rays nearly parallel to the plane
// (|det| below det_epsilon relative to the edge lengths) miss.
inline std::optional<TriangleHit> intersect_triangle(const Ray& ray, const glm::vec3& a,
                                                     const glm::vec3& b, const glm::vec3& c,
                                                     float t_epsilon = 1e-6f) {
  const glm::vec3 e1 = b - a, e2 = c - a;
  const glm::vec3 p = glm::cross(ray.direction, e2);
  const float det = glm::dot(e1, p);
  if (det == 0.0f) return std::nullopt;
  const float inv_det = 1.0f / det;
  const glm::vec3 s = ray.origin - a;
  const float u = glm::dot(s, p) * inv_det;
  if (u < 0.0f || u > 1.0f) return std::nullopt;
  const glm::vec3 q = glm::cross(s, e1);
  const float v = glm::dot(ray.direction, q) * inv_det;
  if (v < 0.0f || u + v > 1.0f) return std::nullopt;
  const float t = glm::dot(e2, q) * inv_det;
  if (!(t > std::max(ray.t_min, t_epsilon) && t < ray.t_max)) return std::nullopt;
  // The determinant epsilon, relative to |e1| |e2| |d| and compared squared: checked last, since
  // most tests have failed above and it needs no square roots this way.
  const float scale2 = glm::dot(e1, e1) * glm::dot(e2, e2) * glm::dot(ray.direction, ray.direction);
  if (!(det * det > 1e-24f * scale2)) return std::nullopt;
  return TriangleHit{t, u, v, 0};
}

}  // namespace farm
