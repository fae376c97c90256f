#pragma once
// Job -> Scene: loads each model once (a file used by several objects is shared), applies object
// transforms and material overrides, and picks the camera and lights (the job's, else the first
// model's).
#include <memory>

#include "renderer/job/job.h"
#include "renderer/loaders/model_library.h"
#include "renderer/scene/scene.h"

namespace farm {

Scene build_scene(const Job& job);
// The same with the models from `models`, which keeps them for the job's other frames.
Scene build_scene(const Job& job, ModelLibrary& models);

// A job's scene and the models it was built from (kept for its other frames).
struct LoadedScene {
  std::shared_ptr<ModelLibrary> models;
  Scene scene;
};

// build_scene with a library of its own, from the job's asset root. Callable on any thread
// (`farm render` loads while its embedded farm is being set up).
LoadedScene load_job_scene(const Job& job);

}  // namespace farm
