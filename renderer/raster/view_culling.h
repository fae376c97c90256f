#pragma once
// Whether a mesh can be skipped before its vertex stage: its whole box lies beyond one plane of
// the view frustum. A frame of many objects, most of them out of sight (a crowd, a forest, a city
// block), then transforms and sets up only what the camera may see.
#include <glm/mat4x4.hpp>

#include "renderer/geometry/aabb.h"

namespace farm::raster {

// True when every point of `model_box`, carried by `model_to_clip`, lies outside one plane of
// the view frustum (near, far, left, right, bottom, top) by a margin that the float vertex stage
// cannot round across: each of the mesh's triangles would then have been dropped by the set-up
// (its vertices share an outcode, or it covers no sample of the image), so skipping the mesh
// leaves every pixel, depth and AOV as they were. Worked out in double at the box's eight
// corners (a plane's distance is linear in clip space, so its extreme is at a corner). False for
// an empty or non-finite box.
bool wholly_outside_view(const AABB& model_box, const glm::mat4& model_to_clip);

}  // namespace farm::raster
