#pragma once
// Job -> Scene: loads each model once (a file used by several objects is shared), applies object
// transforms and material overrides, and picks the camera and lights (the job's, else the first
// model's).
#include "renderer/job/job.h"
#include "renderer/loaders/model_library.h"
#include "renderer/scene/scene.h"

namespace farm {

Scene build_scene(const Job& job);
// The same with the models from `models`, which keeps them for the job's other frames.
Scene build_scene(const Job& job, ModelLibrary& models);

}  // namespace farm
