#include "renderer/job/animation_binding.h"

#include <fmt/format.h>

#include <algorithm>
#include <initializer_list>
#include <string_view>

#include "renderer/job/job_checks.h"

namespace farm {

namespace {

using F = SceneField;

bool is_number_field(SceneField f) {
  switch (f) {
    case F::RotateDegrees:
    case F::MaterialShininess:
    case F::MaterialIor:
    case F::MaterialTransmission:
    case F::CameraFovY:
    case F::CameraNear:
    case F::CameraFar:
    case F::CameraAspect: return true;
    default: return false;
  }
}

// Walks a path under scene along the job format (jobs/README.md), as far as keyframes go: the
// objects, keys and indices on the way to a field.
class FormatWalk {
 public:
  FormatWalk(const std::vector<JsonPathStep>& steps, const std::string& path, const JsonValue& at)
      : steps_(steps), path_(path), at_(at) {}

  // The next step, a key of the object at where(): the index of `animatable`, the keys that lead
  // to values keyframes write. `others` are the object's keys they cannot write.
  std::size_t key(std::initializer_list<std::string_view> animatable,
                  std::initializer_list<std::string_view> others = {}) {
    if (done()) not_a_value("an object");
    const JsonPathStep& step = steps_[next_];
    if (step.key.empty()) names_nothing();
    const std::string alternatives = join_alternatives(animatable);
    if (std::find(others.begin(), others.end(), step.key) != others.end()) {
      at_.fail(fmt::format("'{}' cannot be animated (keyframes animate {} of {})", path_, alternatives, where_));
    }
    const auto it = std::find(animatable.begin(), animatable.end(), step.key);
    if (it == animatable.end()) {
      at_.fail(fmt::format("'{}': {} has no key '{}' (expected {})", path_, where_, step.key, alternatives));
    }
    where_ = json_path_key(where_, step.key);
    ++next_;
    return static_cast<std::size_t>(it - animatable.begin());
  }

  // The next step, an index of the array at where() (the document holds that element).
  std::size_t index() {
    if (done()) not_a_value("an array");
    const JsonPathStep& step = steps_[next_];
    if (!step.key.empty()) names_nothing();
    where_ = json_path_index(where_, step.index);
    ++next_;
    return step.index;
  }

  // After a field: nothing, or [i] of a vector.
  std::optional<std::size_t> component(SceneField field) {
    if (done()) return std::nullopt;
    const JsonPathStep& step = steps_[next_];
    if (is_number_field(field) || !step.key.empty() || step.index >= 3 || next_ + 1 < steps_.size()) names_nothing();
    return step.index;
  }

  const std::string& where() const { return where_; }

 private:
  bool done() const { return next_ == steps_.size(); }
  [[noreturn]] void names_nothing() const { at_.fail(fmt::format("'{}' names nothing in the job", path_)); }
  [[noreturn]] void not_a_value(std::string_view what) const {
    at_.fail(fmt::format("'{}' is {}, not a number or a vector", path_, what));
  }

  const std::vector<JsonPathStep>& steps_;
  const std::string& path_;
  const JsonValue& at_;
  std::size_t next_ = 1;  // steps_[0] is scene
  std::string where_ = "scene";
};

}  // namespace

bool is_camera_field(SceneField f) { return f >= F::CameraPosition && f <= F::CameraAspect; }

Binding resolve_binding(const std::vector<JsonPathStep>& steps, const std::string& path, const JsonValue& at) {
  FormatWalk walk(steps, path, at);
  Binding b;
  switch (walk.key({"objects", "camera", "lights", "ambient", "background"})) {
    case 0: {
      b.owner = walk.index();
      switch (walk.key({"translate", "rotate", "scale", "material"}, {"file", "animation"})) {
        case 0: b.field = F::Translate; break;
        case 1: b.field = walk.key({"axis", "degrees"}) == 0 ? F::RotateAxis : F::RotateDegrees; break;
        case 2: b.field = F::Scale; break;
        default: {
          constexpr SceneField kMaterial[] = {F::MaterialAmbient,   F::MaterialDiffuse, F::MaterialSpecular,
                                              F::MaterialEmission,  F::MaterialShininess, F::MaterialIor,
                                              F::MaterialTransmission};
          b.field = kMaterial[walk.key(
              {"ambient", "diffuse", "specular", "emission", "shininess", "ior", "transmission"}, {"emission_sides"})];
        }
      }
      break;
    }
    case 1: {
      constexpr SceneField kCamera[] = {F::CameraPosition, F::CameraTarget, F::CameraUp, F::CameraFovY,
                                        F::CameraNear,     F::CameraFar,    F::CameraAspect};
      b.field = kCamera[walk.key({"position", "target", "up", "fov_y", "near", "far", "aspect"})];
      break;
    }
    case 2:
      b.owner = walk.index();
      b.field = walk.key({"position", "intensity"}) == 0 ? F::LightPosition : F::LightIntensity;
      break;
    case 3: b.field = F::Ambient; break;
    default: b.field = F::Background;
  }
  b.field_path = walk.where();
  b.component = walk.component(b.field);
  return b;
}

std::vector<std::size_t> key_shapes(const Binding& b) {
  if (b.component || is_number_field(b.field)) return {0};
  if (b.field == F::LightIntensity) return {0, 3};  // a number means grey
  return {3};
}

void write_field(const AnimatedField& f, const double (&x)[3], JobScene& scene, const std::string& file) {
  const JsonPlace at{file, f.path};
  if (f.field < F::CameraPosition) {
    ObjectTransform& t = scene.objects[f.owner].transform;
    MaterialOverride& m = scene.objects[f.owner].material;
    switch (f.field) {
      case F::Translate: t.translate = at.vec3(x); break;
      case F::RotateAxis: t.rotate_axis = unit_axis(at.vec3(x), at); break;
      case F::RotateDegrees: t.rotate_degrees = at.real(x[0]); break;
      case F::Scale:
        t.scale = at.vec3(x);
        check_scale(t.scale, at);
        break;
      case F::MaterialAmbient: m.ambient = at.vec3(x, kRadiometric); break;
      case F::MaterialDiffuse: m.diffuse = at.vec3(x, kRadiometric); break;
      case F::MaterialSpecular: m.specular = at.vec3(x, kRadiometric); break;
      case F::MaterialEmission: m.emission = at.vec3(x, kRadiometric); break;
      case F::MaterialShininess: m.shininess = at.real(x[0], kShininessRange); break;
      case F::MaterialIor: m.ior = at.real(x[0], kIorRange); break;
      default: m.transmission = at.real(x[0], kTransmissionRange);
    }
    return;
  }
  if (is_camera_field(f.field)) {
    // A job without a camera animates the default one, as if it wrote "camera": {} (not the model's).
    Camera& cam = scene.camera ? *scene.camera : scene.camera.emplace();
    switch (f.field) {
      case F::CameraPosition: cam.position = at.vec3(x); break;
      case F::CameraTarget: cam.target = at.vec3(x); break;
      case F::CameraUp: cam.up = at.vec3(x); break;
      case F::CameraFovY: cam.fov_y_degrees = at.real(x[0], kFovYRange); break;
      case F::CameraNear: cam.near = at.real(x[0], kCameraPositive); break;
      case F::CameraFar: cam.far = at.real(x[0], kCameraPositive); break;
      default: cam.aspect = at.real(x[0], kCameraPositive);
    }
    return;
  }
  switch (f.field) {
    case F::LightPosition: (*scene.lights)[f.owner].position = at.vec3(x); break;
    case F::LightIntensity:
      (*scene.lights)[f.owner].intensity = f.scalar ? glm::vec3(at.real(x[0], kRadiometric)) : at.vec3(x, kRadiometric);
      break;
    case F::Ambient: scene.ambient = at.vec3(x, kRadiometric); break;
    default: scene.background = at.vec3(x, kRadiometric);
  }
}

}  // namespace farm
