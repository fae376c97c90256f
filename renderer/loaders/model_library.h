#pragma once
// The models of one job, each file loaded once however many objects and frames use it: a frame
// that only moves things reuses the loaded meshes (and, through ModelGeometry, their BVHs).
#include <filesystem>
#include <future>
#include <map>
#include <memory>
#include <mutex>

#include "renderer/scene/model.h"

namespace farm {

class ModelLibrary {
 public:
  // Models must lie in `asset_root` (load_model's rule); empty: each model's own folder.
  explicit ModelLibrary(std::filesystem::path asset_root) : asset_root_(std::move(asset_root)) {}

  // The model in `file`, loaded by the first caller (others wait for it). A failed load is not
  // kept: its InputError reaches every caller waiting, and a later call tries again.
  std::shared_ptr<const Model> load(const std::filesystem::path& file);
  // The meshes of `file` that hang from glTF node `node` (Mesh::node), with all the model's
  // materials: a part the scene builder places on its own when an animation moves the node. Made
  // once, so that every frame shares its triangles and BVH.
  std::shared_ptr<const Model> node_part(const std::filesystem::path& file, int node);

 private:
  const std::filesystem::path asset_root_;
  std::mutex mutex_;
  std::map<std::filesystem::path, std::shared_future<std::shared_ptr<const Model>>> models_;
  std::map<std::pair<std::filesystem::path, int>, std::shared_ptr<const Model>> parts_;
};

}  // namespace farm
