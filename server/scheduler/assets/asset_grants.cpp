#include "server/scheduler/assets/asset_grants.h"

namespace farm {

AssetGrants::Lease AssetGrants::grant(const std::string& worker_name, const v1::JobSpec& spec) {
  std::vector<std::string> hashes;
  hashes.reserve(static_cast<std::size_t>(spec.assets_size()));
  for (const v1::AssetRef& ref : spec.assets()) hashes.push_back(ref.sha256());
  std::lock_guard lock(mutex_);
  for (const std::string& sha : hashes) ++count_[{worker_name, sha}];
  return Lease(this, worker_name, std::move(hashes));
}

bool AssetGrants::allowed(const std::string& caller, const std::string& sha256) const {
  std::lock_guard lock(mutex_);
  return count_.contains({caller, sha256}) || count_.contains({std::string(), sha256});
}

void AssetGrants::release(const std::string& name, const std::vector<std::string>& hashes) {
  std::lock_guard lock(mutex_);
  for (const std::string& sha : hashes) {
    const auto it = count_.find({name, sha});
    if (it != count_.end() && --it->second == 0) count_.erase(it);
  }
}

}  // namespace farm
