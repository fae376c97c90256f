#pragma once
// What the frames of one job share, so that a frame which only moves objects, the camera or the
// lights costs a top-level build and no more (docs/architecture.md, "The engine contract"): each model's
// flattened triangles and the bottom-level structures (MeshAccel) built on them, made once on
// first use and kept while any frame's PreparedScene holds this.
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "renderer/accel/mesh_accel.h"
#include "renderer/accel/model_triangles.h"
#include "renderer/scene/model.h"
#include "renderer/util/frame_cache.h"

namespace farm {

class ModelGeometry {
 public:
  // The model's triangles, flattened on the first call for that model (which stays alive here).
  const ModelTriangles& triangles(const std::shared_ptr<const Model>& model);
  // The bottom-level structure of `triangles` (one of this object's) for `accel`, built once:
  // concurrent callers wait for one build, each polling its own `cancel` (RenderStopped).
  std::shared_ptr<const MeshAccel> mesh_accel(const ModelTriangles& triangles, AccelKind accel,
                                              const CancelFlag& cancel);
  // How many models have been flattened so far.
  std::size_t flattened_models();

 private:
  struct Entry {
    std::shared_ptr<const Model> model;
    std::unique_ptr<const ModelTriangles> triangles;
  };
  std::mutex mutex_;
  std::map<const Model*, Entry> models_;
  FrameCache accels_{FrameCache::kUnbounded};
};

}  // namespace farm
