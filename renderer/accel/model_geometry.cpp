#include "renderer/accel/model_geometry.h"

#include <fmt/format.h>

namespace farm {

const ModelTriangles& ModelGeometry::triangles(const std::shared_ptr<const Model>& model) {
  std::lock_guard lock(mutex_);
  Entry& e = models_[model.get()];
  if (!e.triangles) {
    e.model = model;
    e.triangles = std::make_unique<const ModelTriangles>(*model);
  }
  return *e.triangles;
}

std::size_t ModelGeometry::flattened_models() {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& [model, entry] : models_) n += entry.triangles ? 1 : 0;
  return n;
}

std::shared_ptr<const MeshAccel> ModelGeometry::mesh_accel(const ModelTriangles& triangles, AccelKind accel,
                                                           const CancelFlag& cancel) {
  const std::string key = fmt::format("{} {}", static_cast<const void*>(&triangles), to_string(accel));
  return accels_.get_or_build<MeshAccel>(key, cancel, [&] {
    return std::shared_ptr<const MeshAccel>(build_mesh_accel(triangles, accel, cancel));
  });
}

}  // namespace farm
