#pragma once
// Light arriving from infinitely far away in every direction (docs/architecture.md, "Environment
// light"): a constant radiance, or a lat-long map times it, scaled by an intensity and turned
// about the world's up axis. The map's directions are Mitsuba 3's `envmap`'s, so that one EXR
// lights both renderers alike: u = atan2(x, -z) / 2pi (wrapped into [0, 1)), v = acos(y) / pi,
// the first row straight up. A direction's radiance is the map's bilinear value there.
//
// Every engine sees it where a ray leaves the scene; the rasterizer and the Whitted tracer take
// their ambient term from its irradiance (nine spherical harmonics, Ramamoorthi and Hanrahan
// 2001); the path tracer samples it by luminance and weighs that against BSDF sampling (MIS).
#include <cstdint>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <memory>
#include <optional>
#include <vector>

#include "renderer/scene/material.h"
#include "renderer/scene/scene.h"
#include "renderer/texture/texture.h"

namespace farm {

class EnvironmentLight {
 public:
  // `map` null: the same radiance from every direction. Throws std::invalid_argument for a
  // negative or non-finite radiance or intensity.
  EnvironmentLight(glm::vec3 radiance, float intensity, float rotation_degrees, std::shared_ptr<const Texture> map);

  // The radiance arriving along -direction, that is from `direction` (world space; any length).
  glm::vec3 radiance(const glm::vec3& direction) const;

  // Irradiance on a surface facing the unit world `normal`, from the whole environment with
  // nothing in the way. Exact for a constant environment (pi times its radiance); for a map, its
  // first nine spherical harmonics (within 10% of the true irradiance for any lighting).
  glm::vec3 irradiance(const glm::vec3& normal) const;

  struct Sample {
    glm::vec3 direction{0.0f};  // unit, world space, towards the environment
    glm::vec3 radiance{0.0f};   // radiance(direction)
    float pdf = 0.0f;           // solid-angle density with which sample() picks it
  };
  // A direction picked in proportion to the map's luminance (times sin(theta), the texel's share
  // of the sphere), or uniformly over the sphere for a constant environment; u1, u2 in [0, 1).
  // None for a black environment.
  std::optional<Sample> sample(float u1, float u2) const;
  // The density sample() has for `direction` (world space, unit).
  float pdf(const glm::vec3& direction) const;

  const Texture* map() const { return map_.get(); }

 private:
  glm::vec3 to_map(const glm::vec3& world) const;  // world direction -> the map's frame
  glm::vec3 to_world(const glm::vec3& map) const;
  void build_distribution();
  void project_irradiance();

  glm::vec3 scale_{1.0f};  // radiance * intensity
  float cos_rotation_ = 1.0f, sin_rotation_ = 0.0f;
  std::shared_ptr<const Texture> map_;
  TextureSampler sampler_;

  // The sampling distribution over one level of the map: each row's running sums of texel
  // weight (columns + 1 entries a row), and the running sums of the rows' totals.
  int level_ = 0, columns_ = 0, rows_ = 0;
  std::vector<float> column_cdf_;  // rows_ * (columns_ + 1), each row's normalised
  std::vector<float> row_cdf_;     // rows_ + 1, normalised
  std::vector<float> weight_;      // rows_ * columns_: each texel's luminance * sin(theta)
  double weight_mean_ = 0.0;       // of weight_: pdf_uv = weight / weight_mean_

  glm::vec3 sh_[9]{};  // irradiance's coefficients, the cosine's convolution included
};

// The radiance a ray leaving the scene along `direction` sees: the environment's, or the
// constant background of a scene without one.
inline glm::vec3 background_radiance(const Scene& scene, const glm::vec3& direction) {
  return scene.environment ? scene.environment->radiance(direction) : scene.background;
}

// The ambient term's light for `material` at unit `normal`, seen from unit `to_eye` (what
// blinn_phong.h multiplies by ka). Without an environment, the scene's constant ambient. With
// one, what its light does to a Lambertian layer of colour kd and a glossy one of colour ks:
// kd E(n) / pi + ks E(r) / pi, r the mirror direction of to_eye, the irradiance about r standing
// for a rough lobe's blur of the map. `glossy` false leaves out the ks part where the engine
// traces that reflection itself (Whitted's mirrors and glass).
inline glm::vec3 ambient_light(const Scene& scene, const Material& material, const glm::vec3& normal,
                               const glm::vec3& to_eye, bool glossy = true) {
  if (!scene.environment) return scene.ambient;
  constexpr float kInvPi = 0.318309886f;
  glm::vec3 light = material.diffuse * scene.environment->irradiance(normal) * kInvPi;
  if (glossy && material.specular != glm::vec3(0.0f)) {
    const glm::vec3 mirror = 2.0f * glm::dot(normal, to_eye) * normal - to_eye;
    light += material.specular * scene.environment->irradiance(mirror) * kInvPi;
  }
  return light;
}

}  // namespace farm
