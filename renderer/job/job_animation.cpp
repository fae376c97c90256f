#include "renderer/job/job_animation.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <map>
#include <set>
#include <tuple>

#include "renderer/util/input_error.h"

namespace farm {

namespace {

using Json = nlohmann::json;

// Keys per track and values per key: a vector of the job has at most 3 components; a track of
// more keys than a job has frames cannot be needed.
constexpr std::size_t kMaxKeys = 100'000;
constexpr std::size_t kMaxComponents = 4;

bool key_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// "scene.objects[0].rotate.degrees" -> scene, objects, [0], rotate, degrees. nullopt when it is
// not such a path.
std::optional<std::vector<JsonPathStep>> parse_path(const std::string& path) {
  std::vector<JsonPathStep> steps;
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) return std::nullopt;
      std::size_t index = 0;
      const auto [end, ec] = std::from_chars(path.data() + i + 1, path.data() + close, index);
      if (ec != std::errc() || end != path.data() + close) return std::nullopt;
      steps.push_back({"", index});
      i = close + 1;
      continue;
    }
    if (path[i] == '.') {
      if (steps.empty()) return std::nullopt;
      ++i;
    } else if (!steps.empty()) {
      return std::nullopt;  // a key must follow a '.' or start the path
    }
    const std::size_t begin = i;
    while (i < path.size() && key_char(path[i])) ++i;
    if (i == begin) return std::nullopt;
    steps.push_back({path.substr(begin, i - begin), 0});
  }
  if (steps.empty()) return std::nullopt;
  return steps;
}

// What a path finds in the document: the value there, or none. `settable` says whether a missing
// value could be written: every step from the first missing one on is a key (a frame writes the
// field as if the job wrote those keys), while an array's missing element names nothing.
struct Found {
  const Json* value = nullptr;
  bool settable = false;
};

Found find(const Json& doc, const std::vector<JsonPathStep>& steps) {
  const Json* node = &doc;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const JsonPathStep& step = steps[s];
    if (step.key.empty()) {
      if (!node->is_array() || step.index >= node->size()) return {};
      node = &(*node)[step.index];
      continue;
    }
    if (!node->is_object()) return {};
    const auto it = node->find(step.key);
    if (it == node->end()) {
      for (std::size_t rest = s + 1; rest < steps.size(); ++rest) {
        if (steps[rest].key.empty()) return {};
      }
      return {nullptr, true};
    }
    node = &*it;
  }
  return {node, false};
}

// How many numbers a value holds: 0 for a number, n for an array of n numbers; nullopt otherwise.
std::optional<std::size_t> numeric_shape(const Json& v) {
  if (v.is_number()) return 0;
  if (!v.is_array() || v.empty()) return std::nullopt;
  for (const Json& x : v) {
    if (!x.is_number()) return std::nullopt;
  }
  return v.size();
}

std::string shape_text(std::size_t shape) { return shape == 0 ? "a number" : fmt::format("{} numbers", shape); }

std::vector<double> key_value(const JsonValue& v) {
  const Json& raw = v.raw();
  const auto shape = numeric_shape(raw);
  if (!shape || *shape > kMaxComponents) v.fail_expected(fmt::format("a number or up to {} numbers", kMaxComponents));
  std::vector<double> out;
  if (*shape == 0) {
    out.push_back(static_cast<double>(v.real()));
  } else {
    for (const JsonValue& x : v.array()) out.push_back(static_cast<double>(x.real()));
  }
  return out;
}

Interpolation parse_interpolation(const JsonValue& v) {
  const std::string s = v.string();
  for (Interpolation i : {Interpolation::Step, Interpolation::Linear, Interpolation::Smooth}) {
    if (s == to_string(i)) return i;
  }
  v.fail(fmt::format("unknown interpolation '{}' (expected step, linear or smooth)", s.substr(0, 64)));
}

std::string shapes_text(const std::vector<std::size_t>& shapes) {
  std::vector<std::string> texts;
  for (std::size_t shape : shapes) texts.push_back(shape_text(shape));
  return texts.size() == 1 ? texts[0] : fmt::format("{} or {}", texts[0], texts[1]);
}

struct ParsedTrack {
  KeyframeTrack track;
  std::vector<JsonPathStep> steps;  // track.path, parsed
  Binding binding;
  bool scalar = true;  // keys of one number
  // The numbers of the field the track writes, as the document holds them (a component's vector).
  std::vector<double> written;
};

ParsedTrack parse_track(const JsonValue& v, const Json& document) {
  const JsonObject obj = v.object({"value", "interpolation", "keys"});
  ParsedTrack out;
  const JsonValue value = obj.require("value");
  out.track.path = value.string();
  const auto steps = parse_path(out.track.path);
  if (!steps) {
    value.fail(fmt::format("'{}' is not a JSON path such as scene.objects[0].rotate.degrees",
                           out.track.path.substr(0, 64)));
  }
  out.steps = *steps;
  if (out.steps.front().key != "scene" || out.steps.size() < 2) {
    value.fail(fmt::format("'{}': only values under scene can be animated", out.track.path));
  }
  const Found found = find(document, out.steps);
  const Json* target = found.value;
  std::optional<std::size_t> shape;
  if (target) {
    shape = numeric_shape(*target);
    if (!shape) {
      value.fail(fmt::format("'{}' is {}, not a number or a vector", out.track.path, describe_json(*target)));
    }
  } else if (!found.settable) {
    value.fail(fmt::format("'{}' names nothing in the job", out.track.path));
  }
  // Keys not written are added at each frame: the job format must have them.
  out.binding = resolve_binding(out.steps, out.track.path, value);
  const Json* field = out.binding.component
                          ? find(document, {out.steps.begin(), out.steps.end() - 1}).value
                          : target;
  if (field && field->is_array()) {
    for (const Json& x : *field) out.written.push_back(x.get<double>());
  }

  if (auto x = obj.get("interpolation")) out.track.interpolation = parse_interpolation(*x);
  const JsonValue keys = obj.require("keys");
  const std::vector<JsonValue> items = keys.array();
  if (items.empty()) keys.fail("expected at least one key, got an empty array");
  if (items.size() > kMaxKeys) keys.fail(fmt::format("{} keys; at most {}", items.size(), kMaxKeys));
  for (const JsonValue& item : items) {
    const JsonObject key = item.object({"frame", "value"});
    const JsonValue frame = key.require("frame");
    Keyframe k;
    k.frame = static_cast<double>(frame.real());
    if (!out.track.keys.empty() && !(k.frame > out.track.keys.back().frame)) {
      frame.fail(fmt::format("expected a frame after {} (keys in frame order), got {}",
                             out.track.keys.back().frame, k.frame));
    }
    const JsonValue kv = key.require("value");
    k.value = key_value(kv);
    const std::size_t this_shape = kv.raw().is_number() ? 0 : k.value.size();
    if (!shape) {
      // A value the job does not write: the first key says which of the shapes it may have.
      const std::vector<std::size_t> shapes = key_shapes(out.binding);
      if (std::find(shapes.begin(), shapes.end(), this_shape) == shapes.end()) {
        kv.fail(fmt::format("expected {} for {}, got {}", shapes_text(shapes), out.binding.field_path,
                            shape_text(this_shape)));
      }
      shape = this_shape;
    }
    if (this_shape != *shape) {
      kv.fail(fmt::format("expected {} like {}, got {}", shape_text(*shape),
                          target ? out.track.path : json_path_index(keys.path(), 0) + ".value",
                          shape_text(this_shape)));
    }
    out.track.keys.push_back(std::move(k));
  }
  out.scalar = *shape == 0;
  return out;
}

// Fields in the order parse_job reads them: the objects', the camera's, the lights', the scene's.
auto read_order(const AnimatedField& f) {
  const int part = f.field < SceneField::CameraPosition ? 0
                   : is_camera_field(f.field)           ? 1
                   : f.field <= SceneField::LightIntensity ? 2
                                                           : 3;
  return std::tuple{part, f.owner, f.field};
}

}  // namespace

JobAnimation parse_animate(const JsonValue& animate, const nlohmann::json& document) {
  JobAnimation out;
  std::set<std::string> seen;
  std::map<std::pair<SceneField, std::size_t>, std::size_t> field_index;  // by field and owner
  for (const JsonValue& item : animate.array()) {
    ParsedTrack t = parse_track(item, document);
    // Paths are compared as parsed: scene.ambient and scene["ambient"] would be one value.
    std::string canonical;
    for (const JsonPathStep& s : t.steps) canonical += s.key.empty() ? fmt::format("[{}]", s.index) : "." + s.key;
    if (!seen.insert(canonical).second) {
      JsonValue(item.raw()["value"], json_path_key(item.path(), "value"), item.file())
          .fail(fmt::format("'{}' is animated twice", t.track.path));
    }
    const Binding& b = t.binding;
    const auto [at, added] = field_index.try_emplace({b.field, b.owner}, out.fields.size());
    if (added) {
      AnimatedField f;
      f.field = b.field;
      f.owner = b.owner;
      f.path = b.field_path;
      f.scalar = !b.component && t.scalar;
      std::copy_n(t.written.begin(), std::min<std::size_t>(t.written.size(), 3), f.written);
      out.fields.push_back(std::move(f));
    }
    // A field's writers in the job's order: a whole vector, then one of its components, is the
    // vector with that component replaced (and the other way round, the whole vector).
    out.fields[at->second].writers.push_back({out.tracks.size(), b.component});
    out.tracks.push_back(std::move(t.track));
  }
  std::sort(out.fields.begin(), out.fields.end(),
            [](const AnimatedField& a, const AnimatedField& b) { return read_order(a) < read_order(b); });

  const auto scene = document.find("scene");
  if (scene != document.end() && scene->is_object()) {
    if (const auto camera = scene->find("camera"); camera != scene->end() && camera->is_object()) {
      out.camera_keys = {camera->contains("near"), camera->contains("far"), camera->contains("up")};
    }
  }
  for (const AnimatedField& f : out.fields) {
    if (f.field == SceneField::CameraNear) out.camera_keys.near = true;
    if (f.field == SceneField::CameraFar) out.camera_keys.far = true;
    if (f.field == SceneField::CameraUp) out.camera_keys.up = true;
  }
  return out;
}

void animate_scene(const JobAnimation& animation, JobScene& scene, int frame, const std::string& file) {
  try {
    std::vector<std::vector<double>> values;
    values.reserve(animation.tracks.size());
    for (const KeyframeTrack& t : animation.tracks) values.push_back(t.at(frame));
    bool camera_written = false;
    for (const AnimatedField& f : animation.fields) {
      // The camera is checked whole once its fields are written, before the lights are read.
      if (camera_written && !is_camera_field(f.field)) {
        check_camera(*scene.camera, animation.camera_keys, JsonPlace{file, "scene.camera"});
        camera_written = false;
      }
      double x[3] = {f.written[0], f.written[1], f.written[2]};
      for (const AnimatedField::Writer& w : f.writers) {
        const std::vector<double>& v = values[w.track];
        if (w.component) {
          x[*w.component] = v[0];
        } else {
          std::copy_n(v.begin(), std::min<std::size_t>(v.size(), 3), x);
        }
      }
      write_field(f, x, scene, file);
      camera_written = camera_written || is_camera_field(f.field);
    }
    if (camera_written) check_camera(*scene.camera, animation.camera_keys, JsonPlace{file, "scene.camera"});
  } catch (const InputError& e) {
    throw InputError(fmt::format("{} (at frame {}, with the animated values)", e.what(), frame));
  }
}

}  // namespace farm
