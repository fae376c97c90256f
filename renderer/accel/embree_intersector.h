#pragma once
// Embree 3 behind the SceneIntersector interface: one Embree scene per model (shared vertex and
// index buffers from ModelTriangles), one instance per object with the object's transform, so
// Embree's hits use exactly our (object, triangle) numbering.
#include <memory>

#include "renderer/accel/scene_intersector.h"

namespace farm {

// `scene` must outlive the result: Embree reads its triangle indices in place. Throws
// std::runtime_error naming the step when Embree reports an error, and RenderStopped when
// `cancel` asks during a build (Embree's progress callback polls it).
std::unique_ptr<SceneIntersector> build_embree_intersector(const PreparedScene& scene,
                                                           const CancelFlag& cancel = CancelFlag::never());

}  // namespace farm
