#include "renderer/job/keyframes.h"

#include <algorithm>
#include <cstddef>

namespace farm {

std::string_view to_string(Interpolation i) {
  switch (i) {
    case Interpolation::Step: return "step";
    case Interpolation::Linear: return "linear";
    case Interpolation::Smooth: return "smooth";
  }
  return "linear";
}

namespace {

// The slope of component c at key k for Catmull-Rom: between the neighbours, or one-sided at
// the ends (a single key has none: the track is constant).
double slope(const std::vector<Keyframe>& keys, std::size_t k, std::size_t c) {
  const std::size_t before = k == 0 ? 0 : k - 1;
  const std::size_t after = std::min(k + 1, keys.size() - 1);
  if (before == after) return 0.0;
  return (keys[after].value[c] - keys[before].value[c]) / (keys[after].frame - keys[before].frame);
}

}  // namespace

std::vector<double> KeyframeTrack::at(double frame) const {
  if (frame <= keys.front().frame) return keys.front().value;
  if (frame >= keys.back().frame) return keys.back().value;
  // The segment [keys[i], keys[i + 1]) that holds `frame`.
  const auto next = std::upper_bound(keys.begin(), keys.end(), frame,
                                     [](double f, const Keyframe& k) { return f < k.frame; });
  const std::size_t i = static_cast<std::size_t>(next - keys.begin()) - 1;
  const Keyframe& a = keys[i];
  const Keyframe& b = keys[i + 1];
  if (interpolation == Interpolation::Step) return a.value;

  const double h = b.frame - a.frame;
  const double s = (frame - a.frame) / h;
  std::vector<double> out(a.value.size());
  for (std::size_t c = 0; c < out.size(); ++c) {
    if (interpolation == Interpolation::Linear) {
      out[c] = a.value[c] + (b.value[c] - a.value[c]) * s;
      continue;
    }
    // Cubic Hermite on [a, b] with Catmull-Rom slopes (per frame, hence the factor h).
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s;
    const double h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    out[c] = h00 * a.value[c] + h10 * h * slope(keys, i, c) + h01 * b.value[c] +
             h11 * h * slope(keys, i + 1, c);
  }
  return out;
}

}  // namespace farm
