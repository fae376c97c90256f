#pragma once
// The GGX (Trowbridge-Reitz) microfacet model, isotropic, in the local shading frame (z is the
// normal): distribution, Smith masking-shadowing and sampling of the visible normals. Shared by
// the glossy BSDF and the table of its albedo.
#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <numbers>

#include "renderer/util/unit_circle.h"

namespace farm::ggx {

inline float distribution(const glm::vec3& m, float alpha) {
  if (m.z <= 0.0f) return 0.0f;
  const float a2 = alpha * alpha;
  const float t = m.z * m.z * (a2 - 1.0f) + 1.0f;
  return a2 / (std::numbers::pi_v<float> * t * t);
}

inline float smith_lambda(const glm::vec3& w, float alpha) {
  const float cos2 = w.z * w.z;
  if (cos2 <= 0.0f) return 0.0f;
  const float tan2 = std::max(0.0f, 1.0f - cos2) / cos2;
  return 0.5f * (-1.0f + std::sqrt(1.0f + alpha * alpha * tan2));
}

inline float smith_g1(const glm::vec3& w, float alpha) { return 1.0f / (1.0f + smith_lambda(w, alpha)); }

// Height-correlated masking-shadowing.
inline float smith_g2(const glm::vec3& wo, const glm::vec3& wi, float alpha) {
  return 1.0f / (1.0f + smith_lambda(wo, alpha) + smith_lambda(wi, alpha));
}

// Density of the visible normal m seen from wo (Heitz 2018), the distribution sampled below.
inline float visible_normal_pdf(const glm::vec3& wo, const glm::vec3& m, float alpha) {
  if (wo.z <= 0.0f) return 0.0f;
  return smith_g1(wo, alpha) * std::max(0.0f, glm::dot(wo, m)) * distribution(m, alpha) / wo.z;
}

// Samples a normal from the visible-normal distribution: stretch the view to the unit-roughness
// configuration, pick a point on the projected hemisphere, unstretch.
inline glm::vec3 sample_visible_normal(const glm::vec3& wo, float alpha, float u1, float u2) {
  const glm::vec3 v = glm::normalize(glm::vec3(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = v.x * v.x + v.y * v.y;
  const glm::vec3 t1 = len2 > 0.0f ? glm::vec3(-v.y, v.x, 0.0f) / std::sqrt(len2) : glm::vec3(1, 0, 0);
  const glm::vec3 t2 = glm::cross(v, t1);
  const float r = std::sqrt(u1);
  const CosSin phi = unit_circle_point(u2);
  const float p1 = r * phi.cos;
  const float s = 0.5f * (1.0f + v.z);
  const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * phi.sin;
  const glm::vec3 n = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * v;
  return glm::normalize(glm::vec3(alpha * n.x, alpha * n.y, std::max(1e-6f, n.z)));
}

inline glm::vec3 reflect_about(const glm::vec3& w, const glm::vec3& n) { return 2.0f * glm::dot(w, n) * n - w; }

// Directional albedo E(mu) of a white single-scattering GGX lobe seen at cos(theta) = mu, and
// its cosine-weighted hemispherical average, from a table computed once (ggx_albedo.cpp).
float directional_albedo(float alpha, float mu);
float average_albedo(float alpha);

}  // namespace farm::ggx
