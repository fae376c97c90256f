#pragma once
// A job ready to queue: the one value SchedulerCore::submit takes (docs/architecture.md, "The
// data path of a job"). A spec from outside becomes one through SpecCheck (spec_check.h); `farm
// render` makes its own, having parsed the job and built its scene itself. Either way the job is
// parsed once and the parsed value travels with its text: the text is what the store keeps and
// the workers are sent, the Job is what the scheduler reads.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/accel/prepared_scene.h"
#include "renderer/job/job.h"
#include "renderer/image/tile_buffer.h"

namespace farm {

struct ValidatedJob {
  v1::JobSpec spec;                             // what the store records and workers are sent
  std::string scene_hash;                       // scene_hash(spec)
  std::shared_ptr<const Job> job;               // the spec's job, parsed
  std::shared_ptr<const PreparedScene> scene;   // null: the merge's Embree check builds one if it needs it
  // Where the merged frames go. Empty: results/<job id>/ (a job from outside). Preview empty:
  // none. A job with frames gives patterns (a '#' run for the frame number).
  std::filesystem::path exr, preview;
  std::filesystem::path video;  // the job's output.video, when its submitter says where
  // Given each merged frame after its files are written (`farm render --show-bvh` draws on it).
  std::function<void(int frame, TileBuffer&&)> merged;
};

}  // namespace farm
