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

 private:
  const std::filesystem::path asset_root_;
  std::mutex mutex_;
  std::map<std::filesystem::path, std::shared_future<std::shared_ptr<const Model>>> models_;
};

}  // namespace farm
