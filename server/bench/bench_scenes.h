#pragma once
// The scenes `farm bench` and the Google Benchmark binaries measure, built in code so that every
// run measures exactly the same thing.
#include <filesystem>
#include <memory>

#include "renderer/scene/scene.h"

namespace farm::bench {

// Where the lab's cow is looked for when no --model is given: ../shared/assets/dae/cow.dae
// relative to the working directory (the repository root).
std::filesystem::path default_cow_path();

// The lab's set-up: the cow at the origin, camera and light at (2, 2, 2).
Scene single_cow(const std::shared_ptr<const Model>& cow);

// `side` x `side` cows on a grid (100 cows: 585,600 triangles), seen at an angle from above so
// that all of them are in view; one light over the middle.
Scene cow_grid(const std::shared_ptr<const Model>& cow, int side);

// The lab's CBbunny (a Cornell box with the bunny) for the path tracer: its ceiling lamp, a plain
// white quad with a point light under it in the file, made an emitter instead; the file's camera.
Scene cbbunny_area_lit(Model cbbunny);

}  // namespace farm::bench
