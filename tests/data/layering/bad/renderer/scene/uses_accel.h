#pragma once
// A fixture for the layering check: the scene types sit below the acceleration structures built
// over them (the cycle scene/camera.h -> geometry/ray.h -> ... -> scene/model.h, issue #33).
#include "renderer/accel/prepared_scene.h"
