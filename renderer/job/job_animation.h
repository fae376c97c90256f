#pragma once
// A job file's `animate` block (jobs/README.md): keyframe tracks on the job's own values, named
// by JSON paths, checked against the document when the job is parsed and bound there to the
// fields of its JobScene they write (animation_binding.h). A frame is the parsed scene with every
// track's value at that frame written in and checked as parse_job checks it, so frame k of an
// animated job is the still with those values written in by hand, reached without reading JSON.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "renderer/job/animation_binding.h"
#include "renderer/job/job_checks.h"
#include "renderer/job/keyframes.h"
#include "renderer/util/json_reader.h"

namespace farm {

struct JobAnimation {
  std::vector<KeyframeTrack> tracks;
  // The fields the tracks write, in the order parse_job reads them (camera fields together).
  std::vector<AnimatedField> fields;
  CameraKeys camera_keys;  // the camera's keys the job writes or keyframes
};

// Parses `animate` (an array of {value, interpolation, keys}) and checks each track against
// `document`: its path lies under `scene`, names an existing number or vector (or keys not
// written, added at each frame: scene.objects[0].rotate.degrees of an object that gives no
// rotate; an array's element must exist) that the job format lets keyframes write, no two tracks
// animate one value, keys are in frame order and their values have the target's shape.
// InputError naming the JSON path otherwise.
JobAnimation parse_animate(const JsonValue& animate, const nlohmann::json& document);

// Writes every track's value at `frame` into `scene` (the job's scene at any of its frames),
// checked as parse_job checks a value written by hand; a refusal is parse_job's message followed
// by " (at frame N, with the animated values)".
void animate_scene(const JobAnimation& animation, JobScene& scene, int frame, const std::string& file);

}  // namespace farm
