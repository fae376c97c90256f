#pragma once
// A job file's `animate` block (jobs/README.md): keyframe tracks on the job's own values, named
// by JSON paths, checked against the document they animate and written into a copy of it at a
// frame. Writing the values into the document, then reading it as any job is read, is what makes
// frame k of an animated job the same job as a still with those values written in by hand.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "renderer/job/keyframes.h"
#include "renderer/util/json_reader.h"

namespace farm {

// One step of a JSON path: a key of an object or an index of an array.
struct JsonPathStep {
  std::string key;        // empty for an index
  std::size_t index = 0;
};

struct AnimatedValue {
  KeyframeTrack track;
  std::vector<JsonPathStep> steps;  // track.path, parsed
  bool scalar = true;               // a number, not an array of them
};

// Parses `animate` (an array of {value, interpolation, keys}) and checks each track against
// `document`: its path lies under `scene`, names an existing number or vector (or keys not
// written, added at each frame: scene.objects[0].rotate.degrees of an object that gives no
// rotate; an array's element must exist), no two tracks animate one value, keys are in frame order and
// their values have the target's shape. InputError naming the JSON path otherwise.
std::vector<AnimatedValue> parse_animate(const JsonValue& animate, const nlohmann::json& document);

// `document` with every track's value at `frame` written in.
nlohmann::json animated_document(const nlohmann::json& document, const std::vector<AnimatedValue>& values,
                                 double frame);

}  // namespace farm
