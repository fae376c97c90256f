#pragma once
// The job file's rules on the scene's values (jobs/README.md), in one place for the two that apply
// them: parse_job, on the values a job writes (job.cpp), and the keyframe bindings, on the values
// an animation reaches at a frame (animation_binding.cpp). Both report through a JsonPlace, so a
// value refused at a frame gets the message it would get written in by hand.
#include <glm/vec3.hpp>

#include "renderer/scene/camera.h"
#include "renderer/scene/radiance_limit.h"
#include "renderer/util/json_reader.h"

namespace farm {

// Light and colour: what renders to finite pixels (radiance_limit.h): ambient, diffuse, specular
// and emission, a light's intensity, the scene's ambient and background.
inline const NumberRange kRadiometric = NumberRange::between(0.0, kRadianceBound);
inline const NumberRange kShininessRange = NumberRange::at_least(0.0);
inline const NumberRange kIorRange = NumberRange::above(0.0);
inline const NumberRange kTransmissionRange = NumberRange::between(0.0, 1.0);
inline const NumberRange kFovYRange = NumberRange::open(0.0, 180.0);
// A camera's near, far and aspect.
inline const NumberRange kCameraPositive = NumberRange::above(0.0);

// A rotation axis made unit length, in double so tiny but non-zero float axes still normalise;
// a zero axis fails at `at`.
glm::vec3 unit_axis(const glm::vec3& axis, const JsonPlace& at);

// A zero scale factor flattens the object and makes the normal matrix singular: fails at at[i].
void check_scale(const glm::vec3& scale, const JsonPlace& at);

// Which of a camera's keys the job gives (written, or keyframed): a message names the key given,
// or says that the value it refuses is the default.
struct CameraKeys {
  bool near = false;
  bool far = false;
  bool up = false;
};

// far > near, and a view basis that is not degenerate in float (glm::lookAt); fails at `camera`
// (scene.camera) or at its far, near or up.
void check_camera(const Camera& cam, const CameraKeys& given, const JsonPlace& camera);

}  // namespace farm
