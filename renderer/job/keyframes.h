#pragma once
// Keyframed job values (jobs/README.md, "animate"): a number or a vector of the job, named by its
// JSON path, given at key frames and interpolated between them. Values before the first key and
// after the last hold. Each component is interpolated on its own, so a rotation given as an angle
// in degrees turns through the angles in between (720 degrees is two turns), never through a
// blend of matrices.
#include <string>
#include <string_view>
#include <vector>

namespace farm {

enum class Interpolation {
  Step,    // a key's value holds until the next key
  Linear,  // straight between neighbouring keys
  Smooth,  // Catmull-Rom: a cubic through the keys, its slope at each the slope between its
           // neighbours (one-sided at the first and last key), for keys at any spacing
};

std::string_view to_string(Interpolation i);

struct Keyframe {
  double frame = 0.0;
  std::vector<double> value;  // one number, or a vector's components
};

struct KeyframeTrack {
  std::string path;  // the JSON path of the animated value, as written: scene.camera.fov_y
  Interpolation interpolation = Interpolation::Linear;
  std::vector<Keyframe> keys;  // at least one, frames strictly increasing, all values one size

  // The value at `frame`.
  std::vector<double> at(double frame) const;
};

}  // namespace farm
