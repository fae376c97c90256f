#include "renderer/job/job_animation.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <set>

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
// value could be added: every step from the first missing one on is a key (an object and its
// keys are added as needed), while an array's missing element names nothing.
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

AnimatedValue parse_track(const JsonValue& v, const Json& document) {
  const JsonObject obj = v.object({"value", "interpolation", "keys"});
  AnimatedValue out;
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
  // Keys not written are added at each frame; reading the job then says whether such keys exist.

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
    if (!shape) shape = this_shape;
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

// The container of the path's last step, objects on the way added where keys are missing
// (parse_animate checked that only keys are).
Json* find_mutable(Json& doc, const std::vector<JsonPathStep>& steps) {
  Json* node = &doc;
  for (std::size_t s = 0; s + 1 < steps.size(); ++s) {
    node = steps[s].key.empty() ? &(*node)[steps[s].index] : &(*node)[steps[s].key];
    if (node->is_null()) *node = Json::object();
  }
  return node;
}

}  // namespace

std::vector<AnimatedValue> parse_animate(const JsonValue& animate, const nlohmann::json& document) {
  std::vector<AnimatedValue> out;
  std::set<std::string> seen;
  for (const JsonValue& item : animate.array()) {
    AnimatedValue v = parse_track(item, document);
    // Paths are compared as parsed: scene.ambient and scene["ambient"] would be one value.
    std::string canonical;
    for (const JsonPathStep& s : v.steps) canonical += s.key.empty() ? fmt::format("[{}]", s.index) : "." + s.key;
    if (!seen.insert(canonical).second) {
      JsonValue(item.raw()["value"], json_path_key(item.path(), "value"), item.file())
          .fail(fmt::format("'{}' is animated twice", v.track.path));
    }
    out.push_back(std::move(v));
  }
  return out;
}

nlohmann::json animated_document(const nlohmann::json& document, const std::vector<AnimatedValue>& values,
                                 double frame) {
  Json doc = document;
  for (const AnimatedValue& v : values) {
    const std::vector<double> x = v.track.at(frame);
    Json& parent = *find_mutable(doc, v.steps);
    const JsonPathStep& last = v.steps.back();
    Json value = v.scalar ? Json(x[0]) : Json(x);
    if (last.key.empty()) {
      parent[last.index] = std::move(value);
    } else {
      parent[last.key] = std::move(value);
    }
  }
  return doc;
}

}  // namespace farm
