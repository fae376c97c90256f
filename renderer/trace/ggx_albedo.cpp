// Tabulated albedo of the single-scattering GGX lobe, for the multiple-scattering term of the
// glossy BSDF (Kulla and Conty 2017): single scattering loses the light that bounces between
// microfacets, up to a quarter of it for rough surfaces at grazing angles, and a white furnace
// shows that as a dark rim. The table is computed here by quadrature, not shipped as data.
#include <array>

#include "renderer/trace/ggx.h"

namespace farm::ggx {
namespace {

constexpr int kAlphaSteps = 32;  // alpha = i / (kAlphaSteps - 1)
constexpr int kMuSteps = 32;     // mu = j / (kMuSteps - 1)
constexpr int kRadialStrata = 64;   // visible-normal samples per entry: radial x angular
constexpr int kAngularStrata = 32;

struct AlbedoTable {
  std::array<std::array<float, kMuSteps>, kAlphaSteps> directional{};
  std::array<float, kAlphaSteps> average{};

  AlbedoTable() {
    for (int i = 0; i < kAlphaSteps; ++i) {
      const float alpha = std::max(1e-3f, static_cast<float>(i) / (kAlphaSteps - 1));
      for (int j = 0; j < kMuSteps; ++j) {
        const float mu = std::max(1e-3f, static_cast<float>(j) / (kMuSteps - 1));
        directional[i][j] = integrate(alpha, mu);
      }
      // E_avg = 2 * integral of E(mu) mu dmu, by the trapezoid rule on the same grid.
      double sum = 0.0;
      for (int j = 1; j < kMuSteps; ++j) {
        const double mu0 = static_cast<double>(j - 1) / (kMuSteps - 1), mu1 = static_cast<double>(j) / (kMuSteps - 1);
        sum += 0.5 * (directional[i][j - 1] * mu0 + directional[i][j] * mu1) * (mu1 - mu0);
      }
      average[i] = static_cast<float>(2.0 * sum);
    }
  }

  // With visible normals sampled, each reflected direction weighs G2 / G1(wo); directions that
  // point below the surface are the energy lost to the masking. The lost directions come from
  // the steepest normals, u1 near 1 (for smooth surfaces only the last percent), so the radial
  // strata are packed there: u1 = 1 - w^3 with w uniform, weighted by du1/dw = 3 w^2.
  static float integrate(float alpha, float mu) {
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
};

const AlbedoTable& table() {
  static const AlbedoTable instance;  // thread-safe, on first use
  return instance;
}

// Position of x in [0, 1] on a grid of n points: lower index and fraction.
std::pair<int, float> grid_position(float x, int n) {
  const float f = std::clamp(x, 0.0f, 1.0f) * static_cast<float>(n - 1);
  const int i = std::min(static_cast<int>(f), n - 2);
  return {i, f - static_cast<float>(i)};
}

}  // namespace

float directional_albedo(float alpha, float mu) {
  const auto [i, fa] = grid_position(alpha, kAlphaSteps);
  const auto [j, fm] = grid_position(mu, kMuSteps);
  const auto& e = table().directional;
  const float lo = e[i][j] + (e[i][j + 1] - e[i][j]) * fm;
  const float hi = e[i + 1][j] + (e[i + 1][j + 1] - e[i + 1][j]) * fm;
  return lo + (hi - lo) * fa;
}

float average_albedo(float alpha) {
  const auto [i, fa] = grid_position(alpha, kAlphaSteps);
  const auto& e = table().average;
  return e[i] + (e[i + 1] - e[i]) * fa;
}

}  // namespace farm::ggx
