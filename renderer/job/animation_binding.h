#pragma once
// What a keyframe track writes (jobs/README.md, "Keyframes"): the field of the parsed JobScene its
// JSON path names, resolved once when the job is parsed, and that field's value at a frame written
// in with the checks parse_job applies to the value written by hand (job_checks.h). So frame k is
// the job with the values at k written in, reached without editing or reading JSON again.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "renderer/job/job.h"
#include "renderer/util/json_reader.h"

namespace farm {

// One step of a JSON path: a key of an object or an index of an array.
struct JsonPathStep {
  std::string key;        // empty for an index
  std::size_t index = 0;
};

// The values of a JobScene that keyframes write, in the order parse_job reads them, so that the
// first value refused at a frame is the one the job written by hand would be refused for.
enum class SceneField {
  // scene.objects[i]
  Translate, RotateAxis, RotateDegrees, Scale,
  MaterialAmbient, MaterialDiffuse, MaterialSpecular, MaterialEmission,
  MaterialShininess, MaterialIor, MaterialTransmission,
  // scene.camera
  CameraPosition, CameraTarget, CameraUp, CameraFovY, CameraNear, CameraFar, CameraAspect,
  // scene.lights[i]
  LightPosition, LightIntensity,
  // scene
  Ambient, Background,
};

bool is_camera_field(SceneField f);

// What a track's path names: a field (of object or light `owner`), whole or one component.
struct Binding {
  SceneField field = SceneField::Translate;
  std::size_t owner = 0;
  std::optional<std::size_t> component;  // [i] of a vector
  std::string field_path;                // as parse_job names it: scene.objects[0].rotate.axis
};

// `steps` (a path from "scene" that names a value the job holds, or keys it does not write) as a
// binding. A path the job format has no number or vector for (scene.camera.zoom,
// scene.objects[0].animation, scene.objects[0].rotate) fails at `at`, naming `path`.
Binding resolve_binding(const std::vector<JsonPathStep>& steps, const std::string& path, const JsonValue& at);

// The shapes a key's value may have for `b`: 0 for a number, 3 for a vector (an intensity: both).
std::vector<std::size_t> key_shapes(const Binding& b);

// One field and the tracks that write it, in the order the job lists them (a whole vector, then
// one of its components, is the vector with that component replaced).
struct AnimatedField {
  SceneField field = SceneField::Translate;
  std::size_t owner = 0;
  std::string path;   // the field's JSON path
  bool scalar = true;  // a number (an intensity keyframed as one number is grey)
  // Its numbers as the job writes them (rotate.axis before it is normalised): what components
  // no track writes hold.
  double written[3] = {0.0, 0.0, 0.0};
  struct Writer {
    std::size_t track;
    std::optional<std::size_t> component;
  };
  std::vector<Writer> writers;
};

// Writes `x`, the field's numbers at a frame, into `scene`, refused as parse_job refuses them
// written by hand: each number at its JSON path, then the field's own rule (a non-zero scale, a
// non-zero rotate axis). A camera field makes the default camera where the job gives none; the
// camera as a whole is left to check_camera.
void write_field(const AnimatedField& f, const double (&x)[3], JobScene& scene, const std::string& file);

}  // namespace farm
