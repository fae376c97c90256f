#include "renderer/scene/model_library.h"

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

}  // namespace farm
