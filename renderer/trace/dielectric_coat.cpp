// The coat's tables (dielectric_coat.h), one per index of refraction on the grid: integrated by
// quadrature (dielectric_coat_quadrature.h) by the build, not shipped as data.
#include "renderer/trace/dielectric_coat.h"

#include <algorithm>
#include <array>
#include <utility>

#include "renderer/trace/dielectric_coat_quadrature.h"

namespace farm {
namespace coat {
namespace {

// Integrated by the build (tools/bsdf_tables.cpp, from dielectric_coat_quadrature.h).
constexpr std::array<CoatTable, kEtaSteps> kTables =
#include "coat_tables.inc"
    ;

}  // namespace

const std::array<CoatTable, kEtaSteps>& built_coat_tables() { return kTables; }

}  // namespace coat

namespace {

using coat::kAlphaSteps;
using coat::kEtaPerStep;
using coat::kEtaSteps;
using coat::kMuSteps;

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
    if (we <= 0.0f) continue;
    const coat::CoatTable& table = coat::built_coat_tables()[static_cast<std::size_t>(ei)];
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
