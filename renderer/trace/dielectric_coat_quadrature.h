#pragma once
// The dielectric coat's tables (dielectric_coat.h) by quadrature, one per index of refraction on
// the grid: what dielectric_coat.cpp reads. Integrated on first use, a table took 0.16 s (18% of
// a 2-sample render of jobs/showcase.json) while every other render thread waited on it; so the
// build integrates all 41 with this very code (tools/bsdf_tables.cpp writes them as exact hex
// floats, dielectric_coat.cpp includes them), and a test integrates some again and compares the
// bits. Header-only, so that the generator needs nothing built before it.
#include <algorithm>
#include <array>
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "renderer/trace/fresnel.h"
#include "renderer/trace/ggx.h"

namespace farm::coat {

inline constexpr int kEtaSteps = 41;       // eta = 1 + i / 20, up to 3
inline constexpr float kEtaPerStep = 20.0f;
inline constexpr int kAlphaSteps = 32;     // alpha = i / (kAlphaSteps - 1)
inline constexpr int kMuSteps = 32;        // mu = j / (kMuSteps - 1)

struct CoatTable {
  std::array<std::array<float, kMuSteps>, kAlphaSteps> transmittance{};
  std::array<float, kAlphaSteps> internal_reflectance{};
};

inline float grid_eta(int i) { return 1.0f + static_cast<float>(i) / kEtaPerStep; }
inline float grid_alpha(int i) { return std::max(1e-3f, static_cast<float>(i) / (kAlphaSteps - 1)); }

// The mean over visible normals m seen from `w` (outside: w.z > 0) of what `weigh(m)` returns:
// the expected share of the light that arrives along -w and leaves as `weigh` says.
template <typename Weigh>
double visible_normal_mean(const glm::vec3& w, float alpha, Weigh&& weigh) {
  constexpr int kStrata = 32;  // visible-normal samples per integral: kStrata x kStrata
  double sum = 0.0;
  for (int a = 0; a < kStrata; ++a)
    for (int b = 0; b < kStrata; ++b) {
      const float u1 = (static_cast<float>(a) + 0.5f) / kStrata, u2 = (static_cast<float>(b) + 0.5f) / kStrata;
      sum += weigh(ggx::sample_visible_normal(w, alpha, u1, u2));
    }
  return sum / (kStrata * kStrata);
}

// Light from outside entering through the interface: (1 - F) of it refracts at each microfacet,
// and the refracted ray must escape the microsurface below (G1).
inline float transmittance_by_quadrature(float eta, float alpha, float mu) {
  const glm::vec3 w{std::sqrt(1.0f - mu * mu), 0.0f, mu};
  return static_cast<float>(visible_normal_mean(w, alpha, [&](const glm::vec3& m) {
    const float cos_i = glm::dot(w, m);
    if (cos_i <= 0.0f) return 0.0f;
    const float inv_eta = 1.0f / eta;
    const float cos_t2 = 1.0f - inv_eta * inv_eta * (1.0f - cos_i * cos_i);
    if (cos_t2 <= 0.0f) return 0.0f;
    const glm::vec3 t = -inv_eta * w + (inv_eta * cos_i - std::sqrt(cos_t2)) * m;
    if (t.z >= 0.0f) return 0.0f;
    return (1.0f - fresnel_dielectric(cos_i, 1.0f, eta)) * ggx::smith_g1(t, alpha);
  }));
}

// Diffuse light inside the coat reflected back down by the interface, totally beyond the critical
// angle: the cosine-weighted average over the hemisphere below, 2 * integral of R(mu) mu dmu, the
// geometry mirrored so that the light arrives from above. Total internal reflection makes the
// integrand jump across the visible normals, which a product grid aliases (0.3% off at alpha
// 0.09); points of Roberts' R3 sequence over (mu, u1, u2) do not.
inline float internal_reflectance_by_quadrature(float eta, float alpha) {
  constexpr int kInternalPoints = 16384;  // (mu, u1, u2) points for each internal reflectance
  constexpr double kPhi3 = 1.2207440846057596;  // the real root of x^3 = x + 1
  static constexpr double kSteps[3] = {1.0 / kPhi3, 1.0 / (kPhi3 * kPhi3), 1.0 / (kPhi3 * kPhi3 * kPhi3)};
  double sum = 0.0;
  for (int i = 0; i < kInternalPoints; ++i) {
    const auto at = [i](int axis) {
      const double x = 0.5 + i * kSteps[axis];
      return static_cast<float>(x - std::floor(x));
    };
    const float mu = at(0);
    const glm::vec3 w{std::sqrt(1.0f - mu * mu), 0.0f, mu};
    const glm::vec3 m = ggx::sample_visible_normal(w, alpha, at(1), at(2));
    const float cos_i = glm::dot(w, m);
    if (cos_i <= 0.0f) continue;
    const glm::vec3 reflected = ggx::reflect_about(w, m);
    if (reflected.z <= 0.0f) continue;
    sum += fresnel_dielectric(cos_i, eta, 1.0f) * ggx::smith_g1(reflected, alpha) * mu;
  }
  return static_cast<float>(2.0 * sum / kInternalPoints);
}

// The table of grid index `eta_index`.
inline CoatTable coat_table_by_quadrature(int eta_index) {
  const float eta = grid_eta(eta_index);
  CoatTable table;
  for (int i = 0; i < kAlphaSteps; ++i) {
    const auto a = static_cast<std::size_t>(i);
    const float alpha = grid_alpha(i);
    for (int j = 0; j < kMuSteps; ++j) {
      const float mu = std::max(1e-3f, static_cast<float>(j) / (kMuSteps - 1));
      table.transmittance[a][static_cast<std::size_t>(j)] = transmittance_by_quadrature(eta, alpha, mu);
    }
    table.internal_reflectance[a] = internal_reflectance_by_quadrature(eta, alpha);
  }
  return table;
}

// The tables the build integrated (dielectric_coat.cpp).
const std::array<CoatTable, kEtaSteps>& built_coat_tables();

}  // namespace farm::coat
