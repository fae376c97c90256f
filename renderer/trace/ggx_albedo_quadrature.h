#pragma once
// The GGX albedo table's entries by quadrature (Kulla and Conty 2017): what ggx_albedo.cpp's
// table holds. Computing the 1,024 entries took 453 M instructions (0.1-0.15 s) on the first
// glossy surface a process shaded, while every other render thread waited on it; so the build
// computes them once, with this very code (tools/bsdf_tables.cpp writes them as exact hex
// floats, ggx_albedo.cpp includes them), and a test computes them again and compares the bits.
// Header-only, so that the generator needs nothing built before it.
#include <algorithm>
#include <array>
#include <cmath>

#include "renderer/trace/ggx.h"

namespace farm::ggx {

inline constexpr int kAlbedoAlphaSteps = 32;  // alpha = i / (kAlbedoAlphaSteps - 1)
inline constexpr int kAlbedoMuSteps = 32;     // mu = j / (kAlbedoMuSteps - 1)

struct AlbedoTable {
  std::array<std::array<float, kAlbedoMuSteps>, kAlbedoAlphaSteps> directional{};
  std::array<float, kAlbedoAlphaSteps> average{};
};

// Directional albedo of the single-scattering lobe at (alpha, mu). With visible normals sampled,
// each reflected direction weighs G2 / G1(wo); directions that point below the surface are the
// energy lost to the masking. The lost directions come from the steepest normals, u1 near 1 (for
// smooth surfaces only the last percent), so the radial strata are packed there: u1 = 1 - w^3
// with w uniform, weighted by du1/dw = 3 w^2.
inline float albedo_by_quadrature(float alpha, float mu) {
  constexpr int kRadialStrata = 64;  // visible-normal samples per entry: radial x angular
  constexpr int kAngularStrata = 32;
  const glm::vec3 wo{std::sqrt(1.0f - mu * mu), 0.0f, mu};
  double sum = 0.0;
  for (int a = 0; a < kRadialStrata; ++a) {
    const float w = (static_cast<float>(a) + 0.5f) / kRadialStrata;
    const float u1 = 1.0f - w * w * w, jacobian = 3.0f * w * w;
    for (int b = 0; b < kAngularStrata; ++b) {
      const float u2 = (static_cast<float>(b) + 0.5f) / kAngularStrata;
      const glm::vec3 wi = reflect_about(wo, sample_visible_normal(wo, alpha, u1, u2));
      if (wi.z > 0.0f) sum += jacobian * smith_g2(wo, wi, alpha) / smith_g1(wo, alpha);
    }
  }
  return static_cast<float>(std::min(1.0, sum / (kRadialStrata * kAngularStrata)));
}

// The whole table: E(alpha, mu) on the grid, and per alpha E_avg = 2 * integral of E(mu) mu dmu
// by the trapezoid rule on the same grid.
inline AlbedoTable albedo_table_by_quadrature() {
  AlbedoTable table;
  for (int i = 0; i < kAlbedoAlphaSteps; ++i) {
    const float alpha = std::max(1e-3f, static_cast<float>(i) / (kAlbedoAlphaSteps - 1));
    auto& row = table.directional[static_cast<std::size_t>(i)];
    for (int j = 0; j < kAlbedoMuSteps; ++j) {
      const float mu = std::max(1e-3f, static_cast<float>(j) / (kAlbedoMuSteps - 1));
      row[static_cast<std::size_t>(j)] = albedo_by_quadrature(alpha, mu);
    }
    double sum = 0.0;
    for (int j = 1; j < kAlbedoMuSteps; ++j) {
      const double mu0 = static_cast<double>(j - 1) / (kAlbedoMuSteps - 1);
      const double mu1 = static_cast<double>(j) / (kAlbedoMuSteps - 1);
      sum += 0.5 * (row[static_cast<std::size_t>(j - 1)] * mu0 + row[static_cast<std::size_t>(j)] * mu1) * (mu1 - mu0);
    }
    table.average[static_cast<std::size_t>(i)] = static_cast<float>(2.0 * sum);
  }
  return table;
}

// The table the build computed (ggx_albedo.cpp): what directional_albedo and average_albedo read.
const AlbedoTable& built_albedo_table();

}  // namespace farm::ggx
