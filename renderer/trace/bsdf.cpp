#include "renderer/trace/bsdf.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <numbers>

#include "renderer/trace/fresnel.h"

namespace farm {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

float max_component(const glm::vec3& v) { return std::max({v.x, v.y, v.z}); }

// GGX (Trowbridge-Reitz) normal distribution and Smith masking, isotropic, local frame.
float ggx_d(const glm::vec3& m, float alpha) {
  if (m.z <= 0.0f) return 0.0f;
  const float a2 = alpha * alpha;
  const float t = m.z * m.z * (a2 - 1.0f) + 1.0f;
  return a2 / (kPi * t * t);
}

float smith_lambda(const glm::vec3& w, float alpha) {
  const float cos2 = w.z * w.z;
  if (cos2 <= 0.0f) return 0.0f;
  const float tan2 = std::max(0.0f, 1.0f - cos2) / cos2;
  return 0.5f * (-1.0f + std::sqrt(1.0f + alpha * alpha * tan2));
}

float smith_g1(const glm::vec3& w, float alpha) { return 1.0f / (1.0f + smith_lambda(w, alpha)); }

float smith_g2(const glm::vec3& wo, const glm::vec3& wi, float alpha) {
  return 1.0f / (1.0f + smith_lambda(wo, alpha) + smith_lambda(wi, alpha));
}

// Density of the visible normal m seen from wo (Heitz 2018), the distribution sampled below.
float visible_normal_pdf(const glm::vec3& wo, const glm::vec3& m, float alpha) {
  if (wo.z <= 0.0f) return 0.0f;
  return smith_g1(wo, alpha) * std::max(0.0f, glm::dot(wo, m)) * ggx_d(m, alpha) / wo.z;
}

// Samples a normal from the visible-normal distribution: stretch the view to the unit-roughness
// configuration, pick a point on the projected hemisphere, unstretch.
glm::vec3 sample_visible_normal(const glm::vec3& wo, float alpha, float u1, float u2) {
  const glm::vec3 v = glm::normalize(glm::vec3(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = v.x * v.x + v.y * v.y;
  const glm::vec3 t1 = len2 > 0.0f ? glm::vec3(-v.y, v.x, 0.0f) / std::sqrt(len2) : glm::vec3(1, 0, 0);
  const glm::vec3 t2 = glm::cross(v, t1);
  const float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
  const float p1 = r * std::cos(phi);
  const float s = 0.5f * (1.0f + v.z);
  const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
  const glm::vec3 n = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * v;
  return glm::normalize(glm::vec3(alpha * n.x, alpha * n.y, std::max(1e-6f, n.z)));
}

glm::vec3 reflect_about(const glm::vec3& w, const glm::vec3& n) { return 2.0f * glm::dot(w, n) * n - w; }

// Cosine-weighted hemisphere direction (Malley's method).
glm::vec3 cosine_hemisphere(float u1, float u2) {
  const float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
  return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))};
}

}  // namespace

float Bsdf::roughness_from_shininess(float shininess) {
  return std::clamp(std::sqrt(2.0f / (std::max(shininess, 0.0f) + 2.0f)), 1e-3f, 1.0f);
}

Bsdf::Bsdf(const Material& m) {
  if (m.transmission > 0.0f && m.ior > 1.0f) {
    kind_ = Kind::Dielectric;
    ior_ = m.ior;
    return;
  }
  if (m.is_mirror()) {
    kind_ = Kind::Mirror;
    specular_ = m.specular == glm::vec3(0.0f) ? glm::vec3(1.0f) : glm::min(m.specular, glm::vec3(1.0f));
    return;
  }
  // What the specular layer reflects is not available to the diffuse one below it.
  specular_ = glm::clamp(m.specular, 0.0f, 1.0f);
  diffuse_ = glm::clamp(m.diffuse, 0.0f, 1.0f) * (1.0f - max_component(specular_));
  alpha_ = roughness_from_shininess(m.shininess);
  const float s = max_component(specular_), d = max_component(diffuse_);
  specular_probability_ = s + d > 0.0f ? s / (s + d) : 0.0f;
}

glm::vec3 Bsdf::eval_layered(const glm::vec3& wo, const glm::vec3& wi) const {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return glm::vec3(0.0f);
  glm::vec3 f = diffuse_ / kPi;
  if (specular_probability_ > 0.0f) {
    const glm::vec3 m = glm::normalize(wo + wi);
    f += specular_ * (ggx_d(m, alpha_) * smith_g2(wo, wi, alpha_) / (4.0f * wo.z * wi.z));
  }
  return f;
}

float Bsdf::pdf_layered(const glm::vec3& wo, const glm::vec3& wi) const {
  if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
  float pdf = (1.0f - specular_probability_) * wi.z / kPi;
  if (specular_probability_ > 0.0f) {
    const glm::vec3 m = glm::normalize(wo + wi);
    pdf += specular_probability_ * visible_normal_pdf(wo, m, alpha_) / (4.0f * glm::dot(wo, m));
  }
  return pdf;
}

glm::vec3 Bsdf::eval(const glm::vec3& wo, const glm::vec3& wi) const {
  return kind_ == Kind::Layered ? eval_layered(wo, wi) : glm::vec3(0.0f);
}

float Bsdf::pdf(const glm::vec3& wo, const glm::vec3& wi) const {
  return kind_ == Kind::Layered ? pdf_layered(wo, wi) : 0.0f;
}

std::optional<BsdfSample> Bsdf::sample(const glm::vec3& wo, float u_lobe, float u1, float u2) const {
  BsdfSample s;
  switch (kind_) {
    case Kind::Mirror:
      if (wo.z <= 0.0f) return std::nullopt;
      s.wi = {-wo.x, -wo.y, wo.z};
      s.weight = specular_;
      s.pdf = 1.0f;
      s.specular = true;
      return s;

    case Kind::Dielectric: {
      // Indices on the side wo is on, and on the other side; the normal flipped to wo's side.
      const bool entering = wo.z > 0.0f;
      const float eta_i = entering ? 1.0f : ior_, eta_t = entering ? ior_ : 1.0f;
      const glm::vec3 n{0.0f, 0.0f, entering ? 1.0f : -1.0f};
      const float cos_i = std::fabs(wo.z);
      const float reflectance = fresnel_dielectric(cos_i, eta_i, eta_t);
      s.specular = true;
      if (u_lobe < reflectance) {
        s.wi = {-wo.x, -wo.y, wo.z};
        s.weight = glm::vec3(1.0f);
        s.pdf = reflectance;
        return s;
      }
      const float eta = eta_i / eta_t;
      const float cos_t = std::sqrt(std::max(0.0f, 1.0f - eta * eta * (1.0f - cos_i * cos_i)));
      s.wi = glm::normalize(-eta * wo + (eta * cos_i - cos_t) * n);
      // Radiance is compressed by (eta_i / eta_t)^2 entering a denser medium (it cancels on the
      // way back out).
      s.weight = glm::vec3(eta * eta);
      s.pdf = 1.0f - reflectance;
      return s;
    }

    case Kind::Layered: {
      if (wo.z <= 0.0f) return std::nullopt;
      if (u_lobe < specular_probability_) {
        s.wi = reflect_about(wo, sample_visible_normal(wo, alpha_, u1, u2));
      } else {
        s.wi = cosine_hemisphere(u1, u2);
      }
      if (s.wi.z <= 0.0f) return std::nullopt;
      s.pdf = pdf_layered(wo, s.wi);
      if (!(s.pdf > 0.0f)) return std::nullopt;
      s.weight = eval_layered(wo, s.wi) * s.wi.z / s.pdf;
      return s;
    }
  }
  return std::nullopt;
}

}  // namespace farm
