// The coat's tables (dielectric_coat.h), one per index of refraction on the grid, integrated on
// first use: computed here by quadrature, not shipped as data.
#include "renderer/trace/dielectric_coat.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <mutex>
#include <utility>

#include "renderer/trace/fresnel.h"
#include "renderer/trace/ggx.h"

namespace farm {
namespace {

constexpr int kEtaSteps = 41;       // eta = 1 + i / 20, up to 3
constexpr float kEtaPerStep = 20.0f;
constexpr int kAlphaSteps = 32;     // alpha = i / (kAlphaSteps - 1)
constexpr int kMuSteps = 32;        // mu = j / (kMuSteps - 1)
constexpr int kStrata = 32;         // visible-normal samples per integral: kStrata x kStrata
constexpr int kInternalPoints = 16384;  // (mu, u1, u2) points for each internal reflectance

struct CoatTable {
  std::array<std::array<float, kMuSteps>, kAlphaSteps> transmittance{};
  std::array<float, kAlphaSteps> internal_reflectance{};
};

float grid_alpha(int i) { return std::max(1e-3f, static_cast<float>(i) / (kAlphaSteps - 1)); }

// The mean over visible normals m seen from `w` (outside: w.z > 0) of what `weigh(m)` returns:
// the expected share of the light that arrives along -w and leaves as `weigh` says.
template <typename Weigh>
double visible_normal_mean(const glm::vec3& w, float alpha, Weigh&& weigh) {
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
float transmittance(float eta, float alpha, float mu) {
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
float internal_reflectance(float eta, float alpha) {
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

std::unique_ptr<CoatTable> integrate_table(float eta) {
  auto table = std::make_unique<CoatTable>();
  for (int i = 0; i < kAlphaSteps; ++i) {
    const float alpha = grid_alpha(i);
    for (int j = 0; j < kMuSteps; ++j) {
      const float mu = std::max(1e-3f, static_cast<float>(j) / (kMuSteps - 1));
      table->transmittance[i][j] = transmittance(eta, alpha, mu);
    }
    table->internal_reflectance[i] = internal_reflectance(eta, alpha);
  }
  return table;
}

// The table of grid index i, integrated by the first thread that asks for it.
const CoatTable& table_at(int i) {
  static std::array<std::once_flag, kEtaSteps> once;
  static std::array<std::unique_ptr<CoatTable>, kEtaSteps> tables;
  std::call_once(once[static_cast<std::size_t>(i)], [i] {
    tables[static_cast<std::size_t>(i)] = integrate_table(1.0f + static_cast<float>(i) / kEtaPerStep);
  });
  return *tables[static_cast<std::size_t>(i)];
}

// Position of x in [0, steps - 1] on a grid: lower index and fraction.
std::pair<int, float> grid_position(float x, int steps) {
  const float f = std::clamp(x, 0.0f, static_cast<float>(steps - 1));
  const int i = std::min(static_cast<int>(f), steps - 2);
  return {i, f - static_cast<float>(i)};
}

}  // namespace

DielectricCoat::DielectricCoat(float eta, float alpha) : eta_(std::clamp(eta, 1.0f, 3.0f)) {
  // eta * 20 - 20 is exact for the grid's own indices (1.5 is 10, not 9.99...).
  const auto [e, fe] = grid_position(eta_ * kEtaPerStep - kEtaPerStep, kEtaSteps);
  const auto [a, fa] = grid_position(alpha * (kAlphaSteps - 1), kAlphaSteps);
  int n = 0;
  for (const auto& [ei, we] : {std::pair{e, 1.0f - fe}, std::pair{e + 1, fe}}) {
    if (we <= 0.0f) continue;  // a table never integrated for nothing
    const CoatTable& table = table_at(ei);
    for (const auto& [ai, wa] : {std::pair{a, 1.0f - fa}, std::pair{a + 1, fa}}) {
      rows_[n++] = Row{table.transmittance[static_cast<std::size_t>(ai)].data(), we * wa};
      internal_reflectance_ += we * wa * table.internal_reflectance[static_cast<std::size_t>(ai)];
    }
  }
}

float DielectricCoat::transmittance(float mu) const {
  const auto [j, f] = grid_position(mu * (kMuSteps - 1), kMuSteps);
  float t = 0.0f;
  for (const Row& row : rows_) {
    if (row.values != nullptr) t += row.weight * (row.values[j] + (row.values[j + 1] - row.values[j]) * f);
  }
  return t;
}

}  // namespace farm
