#include "renderer/loaders/model_library.h"

namespace farm {

std::shared_ptr<const Model> ModelLibrary::load(const std::filesystem::path& file) {
  std::promise<std::shared_ptr<const Model>> promise;
  std::shared_future<std::shared_ptr<const Model>> future;
  {
    std::lock_guard lock(mutex_);
    auto [it, added] = models_.try_emplace(file);
    if (added) it->second = promise.get_future().share();
    if (!added) future = it->second;
  }
  if (future.valid()) return future.get();
  try {
    auto model = std::make_shared<const Model>(asset_root_.empty() ? load_model(file) : load_model(file, asset_root_));
    promise.set_value(model);
    return model;
  } catch (...) {
    {
      std::lock_guard lock(mutex_);
      models_.erase(file);
    }
    promise.set_exception(std::current_exception());
    throw;
  }
}

std::shared_ptr<const Model> ModelLibrary::node_part(const std::filesystem::path& file, int node) {
  const std::shared_ptr<const Model> whole = load(file);
  std::lock_guard lock(mutex_);
  std::shared_ptr<const Model>& part = parts_[{file, node}];
  if (!part) {
    auto p = std::make_shared<Model>();
    p->source = whole->source;
    p->materials = whole->materials;
    p->nodes = whole->nodes;
    for (const Mesh& mesh : whole->meshes) {
      if (mesh.node == node) p->meshes.push_back(mesh);
    }
    part = std::move(p);
  }
  return part;
}

}  // namespace farm
