#include "renderer/raster/view_culling.h"

#include <array>
#include <cmath>
#include <glm/vec4.hpp>

#include "renderer/raster/clip_polygon.h"

namespace farm::raster {
namespace {

// A corner's clip-space distance beyond a plane must exceed this share of the magnitudes that
// make it up: the float vertex stage (`model_to_clip` times the point, then the plane's sum, each
// in float) is off by a few ulps of those magnitudes, 1e-6 of them at most.
constexpr double kMargin = 1e-4;

}  // namespace

bool wholly_outside_view(const AABB& model_box, const glm::mat4& model_to_clip) {
  if (model_box.empty()) return false;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(model_box.min[a]) || !std::isfinite(model_box.max[a])) return false;
  }
  const glm::dmat4 m(model_to_clip);
  std::array<glm::dvec4, 8> corners;
  std::array<double, 8> magnitude;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec4 p((c & 1) ? model_box.max.x : model_box.min.x, (c & 2) ? model_box.max.y : model_box.min.y,
                       (c & 4) ? model_box.max.z : model_box.min.z, 1.0);
    corners[c] = m * p;
    // What the float stage's rounding scales with: every product's size, summed.
    double sum = 0.0;
    for (int row = 0; row < 4; ++row) {
      for (int k = 0; k < 4; ++k) sum += std::abs(m[k][row] * p[k]);
    }
    magnitude[c] = sum;
  }
  // The clipper's near and far planes, and the image's edges for the sides.
  for (int plane = 0; plane < kClipPlaneCount; ++plane) {
    bool all_outside = true;
    for (int c = 0; c < 8 && all_outside; ++c) {
      all_outside = clip_plane_distance(corners[c], plane, 1.0) < -kMargin * magnitude[c];
    }
    if (all_outside) return true;
  }
  return false;
}

}  // namespace farm::raster
