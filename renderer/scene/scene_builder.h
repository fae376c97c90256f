#pragma once
// Job -> Scene: loads each model once (a file used by several objects is shared), applies object
// transforms and material overrides, and picks the camera and lights (the job's, else the first
// model's).
#include "renderer/scene/job.h"
#include "renderer/scene/scene.h"

namespace farm {

Scene build_scene(const Job& job);

}  // namespace farm
