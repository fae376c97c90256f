#pragma once
// Blinn-Phong, the one shading function that `raster` and `whitted` share (docs/architecture.md, "Conventions"):
//   ke + ka*ambient + sum over lights of (I/r^2) * (kd*max(0,n.l) + ks*max(0,n.h)^p)
// where ke counts only on the emitting side(s) of the surface (Material::emitted), as in `path`.
// Directional lights contribute I with no falloff. A ray tracer passes a visibility test so
// shadowed lights drop out; the rasterizer has no shadows and sees every light.
#include <cmath>
#include <cstddef>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <span>

#include "renderer/scene/light.h"
#include "renderer/scene/material.h"

namespace farm {

// Where a light's energy comes from, as seen from one surface point.
struct LightIncidence {
  glm::vec3 to_light{0.0f};  // unit
  float distance = 0.0f;     // +inf for directional lights
  glm::vec3 irradiance{0.0f};
};

inline LightIncidence light_incidence(const Light& light, const glm::vec3& point) {
  LightIncidence in;
  if (light.kind == Light::Kind::Directional) {
    in.to_light = -glm::normalize(light.direction);
    in.distance = INFINITY;
    in.irradiance = light.intensity;
    return in;
  }
  const glm::vec3 d = light.position - point;
  const float r2 = glm::dot(d, d);
  in.distance = std::sqrt(r2);
  in.to_light = in.distance > 0.0f ? d / in.distance : glm::vec3(0.0f, 0.0f, 1.0f);
  in.irradiance = r2 > 0.0f ? light.intensity / r2 : glm::vec3(0.0f);
  return in;
}

// One light's reflected radiance; n, to_eye and to_light are unit vectors.
inline glm::vec3 blinn_phong_term(const Material& m, const glm::vec3& n, const glm::vec3& to_eye,
                                  const LightIncidence& in) {
  const float n_dot_l = glm::dot(n, in.to_light);
  if (n_dot_l <= 0.0f) return glm::vec3(0.0f);
  glm::vec3 result = m.diffuse * n_dot_l;
  if (m.specular != glm::vec3(0.0f)) {
    const glm::vec3 h = glm::normalize(in.to_light + to_eye);
    result += m.specular * std::pow(std::max(0.0f, glm::dot(n, h)), m.shininess);
  }
  return in.irradiance * result;
}

struct AllLightsVisible {
  bool operator()(const glm::vec3&, const LightIncidence&, std::size_t) const { return true; }
};

// `n` must face the viewer (flip back faces before calling); `front_side` says whether the viewer
// sees the surface's front face (its winding's side); `visible(point, incidence, light)` decides
// shadowing, `light` the light's index in `lights`.
template <typename Visibility = AllLightsVisible>
glm::vec3 shade_blinn_phong(const Material& m, const glm::vec3& point, const glm::vec3& n,
                            const glm::vec3& to_eye, bool front_side, std::span<const Light> lights,
                            const glm::vec3& ambient, Visibility&& visible = {}) {
  glm::vec3 color = m.emitted(front_side) + m.ambient * ambient;
  for (const Light& light : lights) {
    const LightIncidence in = light_incidence(light, point);
    if (glm::dot(n, in.to_light) <= 0.0f) continue;
    if (!visible(point, in, static_cast<std::size_t>(&light - lights.data()))) continue;
    color += blinn_phong_term(m, n, to_eye, in);
  }
  return color;
}

}  // namespace farm
