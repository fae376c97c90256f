#pragma once
// Which assets a worker may fetch (Scheduler.GetAsset with the `worker` role): only those of the
// jobs it has been given, while it has them. A call to a worker grants the assets of its job to
// the name the worker registered under for as long as the call lasts; a static worker
// (`farm scheduler --worker`) registered under no name, so its grants go to any caller holding
// the worker role. Admins may fetch every asset.
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"

namespace farm {

class AssetGrants {
 public:
  // Grants `spec`'s assets to `worker_name` until the lease is destroyed.
  class Lease {
   public:
    Lease() = default;
    Lease(AssetGrants* grants, std::string name, std::vector<std::string> hashes)
        : grants_(grants), name_(std::move(name)), hashes_(std::move(hashes)) {}
    Lease(Lease&& o) noexcept : grants_(std::exchange(o.grants_, nullptr)), name_(std::move(o.name_)),
                               hashes_(std::move(o.hashes_)) {}
    Lease& operator=(Lease&&) = delete;
    Lease(const Lease&) = delete;
    ~Lease() {
      if (grants_) grants_->release(name_, hashes_);
    }

   private:
    AssetGrants* grants_ = nullptr;
    std::string name_;
    std::vector<std::string> hashes_;
  };

  // `worker_name` empty: any caller with the worker role.
  Lease grant(const std::string& worker_name, const v1::JobSpec& spec);
  bool allowed(const std::string& caller, const std::string& sha256) const;

 private:
  void release(const std::string& name, const std::vector<std::string>& hashes);

  mutable std::mutex mutex_;
  std::map<std::pair<std::string, std::string>, int> count_;  // (name, sha256) -> calls in flight
};

}  // namespace farm
