#pragma once
// A job file (jobs/README.md, version 1), parsed and strictly validated. Every error is an
// InputError whose message starts with the file and names the JSON path, for example
//   jobs/cow.json: scene.objects[2].scale: expected 3 numbers
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "renderer/job/frame_range.h"
#include "renderer/job/render_settings.h"
#include "renderer/job/worker_requirements.h"
#include "renderer/scene/camera.h"
#include "renderer/scene/light.h"
#include "renderer/scene/material.h"
#include "renderer/scene/transform.h"

namespace farm {

// Which of a glTF model's animations an object plays (jobs/README.md, "animation").
struct ObjectAnimation {
  enum class Pick { First, Off, Index, Name } pick = Pick::First;  // First: the model's first, if any
  std::size_t index = 0;
  std::string name;
};

struct JobObject {
  std::filesystem::path file;   // absolute, canonical, checked to lie inside the asset root
  std::string file_as_written;  // as it appears in the job, for messages
  ObjectTransform transform;
  MaterialOverride material;
  ObjectAnimation animation;
};

// scene.environment (jobs/README.md): light from all around, in place of background and ambient.
struct JobEnvironment {
  std::filesystem::path map;   // a lat-long image, confined like a model file; empty: constant
  std::string map_as_written;  // as it appears in the job, for messages
  glm::vec3 radiance{1.0f};    // the constant's radiance, or what multiplies the map
  float intensity = 1.0f;
  float rotate_degrees = 0.0f;  // about the world's +y axis
};

struct JobScene {
  std::vector<JobObject> objects;
  std::optional<Camera> camera;              // absent: the first model camera, else the default
  std::optional<std::vector<Light>> lights;  // absent: the models' lights
  glm::vec3 ambient{0.1f};
  glm::vec3 background{100.0f / 255.0f};
  std::optional<JobEnvironment> environment;
};


struct JobOutput {
  std::filesystem::path image;    // EXR; relative paths are relative to the working directory
  std::filesystem::path preview;  // PNG/JPEG; empty = none
  // The frames' previews as one video, by ffmpeg (video_format.h); empty = none. Only with
  // frames, and then the same for every frame (no '#' run).
  std::filesystem::path video;
};

struct JobAnimation;  // the job's keyframe tracks, bound to the fields they write (job_animation.h)

struct Job {
  std::filesystem::path path;     // the job file
  // Absolute, symlinks resolved: every file the job reads, and every file its models name, lies
  // in here (renderer/util/confined_file.h).
  std::filesystem::path asset_root;
  std::string name;
  JobScene scene;
  RenderSettings render;          // includes the output AOVs
  JobOutput output;
  std::int64_t embree_rays = 0;   // validate.embree_rays
  WorkerRequirements requirements;  // where a farm may render it (farm render ignores them)
  JobCaps caps;                     // how much of a farm it may hold at once (likewise)
  // The job's frames; absent: one still (frame 0). A Job is always one frame's still: the values
  // above, output included, are those of `frame` (the first frame rendered, as parsed; any other
  // through job_at_frame()). `output_patterns` keeps the names with their '#' runs.
  std::optional<FrameRange> frames;
  int frame = 0;
  double seconds = 0.0;  // the frame's time, (frame - start) / fps: what glTF animations play at
  JobOutput output_patterns;
  std::shared_ptr<const JobAnimation> animation;  // null: nothing is keyframed
};

// Every file the job names itself (each object's model, the environment's map), resolved, each
// once, in the order the job first names it: what a submission uploads besides the files the
// models name.
std::vector<std::filesystem::path> job_named_files(const Job& job);

// The frames the job renders: its range's, or the still's frame 0.
std::vector<int> job_frames(const Job& job);
// The job at `frame` (one of job_frames): keyframed values evaluated there, render.frame and
// `frame` set, the output patterns' '#' runs replaced by the frame number. The result is the job
// a still with those values written in by hand would be (with a range of that one frame).
Job job_at_frame(const Job& job, int frame);

struct JobLoadOptions {
  // Model files must resolve inside this folder; empty = the job file's folder.
  std::filesystem::path asset_root;
  // How the person reading a refusal can widen the root, added to a "lies outside the asset root"
  // message (the commands: "give --asset-root DIR ..."); empty where nobody can (a worker).
  std::string asset_root_hint;
  // Model paths resolved by name alone, under asset_root (absolute, and taken as it is): nothing
  // is looked up, so the models need not exist yet. For a scheduler that plans a submission
  // before it holds the job's files (PlanSubmission): it reads the job as it will lay it out. A
  // path that is absolute or leads out of the root is refused as confine_file refuses it.
  bool models_by_name = false;
};

// Parses and validates `path`. Model files must exist; they are not loaded here.
Job load_job(const std::filesystem::path& path, const JobLoadOptions& options = {});
// Same, from JSON text; `path` names the file in messages and anchors relative model paths.
Job parse_job(const std::string& json_text, const std::filesystem::path& path,
              const JobLoadOptions& options = {});
// Same, from the text already read by parse_json_strict (renderer/util/json_reader.h): for a
// caller that also writes the document on (a submission rewriting its model paths), so that the
// text is parsed once.
Job parse_job_document(const nlohmann::json& document, const std::filesystem::path& path,
                       const JobLoadOptions& options = {});
// The text of the job file `path`, read as load_job reads it (a regular file, at most 16 MiB),
// for callers that send the text on as well as parse it: then the file is read once.
std::string read_job_file(const std::filesystem::path& path);

}  // namespace farm
