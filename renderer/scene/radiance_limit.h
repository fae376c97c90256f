#pragma once
// One rule for extreme light, the same in every engine, in process and on the farm (issue #32):
// a sample's radiance is at most kMaxRadiance per channel and never NaN, so a pixel (a mean of at
// most kMaxSpp samples), its variance (a mean of squares) and a merge of passes stay finite
// whatever the scene. Without it a light of intensity 3e38, which a job may name, made +inf
// pixels that the farm's result check rightly calls impossible for an engine.
//
// The bound is far above any light a scene meant (the sun's radiance is about 1e7 W/sr/m^2;
// images are displayed around 1): it changes no pixel of an ordinary render. The job file's
// radiometric values (light intensity, emission, ambient, background) are held to it too, so that
// a typo like 3e38 is refused with its key named instead of rendered clamped.
#include <cmath>
#include <glm/vec3.hpp>

namespace farm {

// sqrt(FLT_MAX / 2^20 samples) is about 1.8e16: squares of 2^20 samples still sum finite. As the
// job file's rules word it (a double), and as the engines hold samples to it (the nearest float).
inline constexpr double kRadianceBound = 1e15;
inline constexpr float kMaxRadiance = static_cast<float>(kRadianceBound);

// `c` within [.., kMaxRadiance] per channel, a NaN channel 0 (a sample with no defined value adds
// nothing, as the path tracer drops it).
// A comparison rather than std::fmin, whose NaN rules (handled first here) GCC keeps by calling libm.
inline float limit_radiance(float c) { return std::isnan(c) ? 0.0f : (c < kMaxRadiance ? c : kMaxRadiance); }
inline glm::vec3 limit_radiance(const glm::vec3& c) {
  return {limit_radiance(c.x), limit_radiance(c.y), limit_radiance(c.z)};
}

}  // namespace farm
