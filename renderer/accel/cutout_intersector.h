#pragma once
// Surfaces that let rays through where their alpha says so (glTF's alphaMode MASK and BLEND;
// docs/architecture.md, §8.4), for every ray engine at once: a hit on a cut-out point is skipped
// and the query goes on past it, for closest hits and shadow rays alike. Wrapped around a
// scene's intersector only when one of its materials is not opaque, so that every other scene
// keeps its queries exactly as they were.
#include <memory>

#include "renderer/accel/scene_intersector.h"

namespace farm {

// Whether any material of `scene` lets rays through anywhere.
bool has_cutouts(const PreparedScene& scene);

// `inner` with cut-out points skipped. A blended surface stops a ray with the probability of its
// coverage, decided by a hash of the ray and the triangle (the same ray always gets the same
// answer, on any thread and tiling). At most kMaxCutoutLayers cut-out hits are passed on one ray;
// the next is taken as it is, so that no input makes a query unbounded.
std::unique_ptr<SceneIntersector> skip_cutouts(const PreparedScene& scene, std::unique_ptr<SceneIntersector> inner);

constexpr int kMaxCutoutLayers = 256;

}  // namespace farm
