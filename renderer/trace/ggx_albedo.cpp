// Tabulated albedo of the single-scattering GGX lobe, for the multiple-scattering term of the
// glossy BSDF (Kulla and Conty 2017): single scattering loses the light that bounces between
// microfacets, up to a quarter of it for rough surfaces at grazing angles, and a white furnace
// shows that as a dark rim. The table is computed by quadrature (ggx_albedo_quadrature.h), by the
// build, not shipped as data.
#include <algorithm>
#include <utility>

#include "renderer/trace/ggx.h"
#include "renderer/trace/ggx_albedo_quadrature.h"

namespace farm::ggx {
namespace {

// Computed by the build (tools/bsdf_tables.cpp, from ggx_albedo_quadrature.h).
constexpr AlbedoTable kTable =
#include "ggx_albedo_table.inc"
    ;

// Position of x in [0, 1] on a grid of n points: lower index and fraction.
std::pair<int, float> grid_position(float x, int n) {
  const float f = std::clamp(x, 0.0f, 1.0f) * static_cast<float>(n - 1);
  const int i = std::min(static_cast<int>(f), n - 2);
  return {i, f - static_cast<float>(i)};
}

}  // namespace

const AlbedoTable& built_albedo_table() { return kTable; }

float directional_albedo(float alpha, float mu) {
  const auto [i, fa] = grid_position(alpha, kAlbedoAlphaSteps);
  const auto [j, fm] = grid_position(mu, kAlbedoMuSteps);
  const auto& e = kTable.directional;
  const float lo = e[i][j] + (e[i][j + 1] - e[i][j]) * fm;
  const float hi = e[i + 1][j] + (e[i + 1][j + 1] - e[i + 1][j]) * fm;
  return lo + (hi - lo) * fa;
}

float average_albedo(float alpha) {
  const auto [i, fa] = grid_position(alpha, kAlbedoAlphaSteps);
  const auto& e = kTable.average;
  return e[i] + (e[i + 1] - e[i]) * fa;
}

}  // namespace farm::ggx
