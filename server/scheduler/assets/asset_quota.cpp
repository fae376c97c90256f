#include "server/scheduler/assets/asset_quota.h"

#include <fmt/format.h>

#include <system_error>
#include <utility>

#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace farm {

namespace fs = std::filesystem;

AssetQuota::AssetQuota(fs::path store_dir, std::uint64_t limit) : dir_(std::move(store_dir)), limit_(limit) {}

AssetQuota::Reservation::Reservation(Reservation&& other) noexcept
    : quota_(std::exchange(other.quota_, nullptr)), bytes_(other.bytes_), owner_(std::move(other.owner_)) {}

AssetQuota::Reservation::~Reservation() {
  if (!quota_) return;
  std::lock_guard lock(quota_->mutex_);
  quota_->reserved_ -= bytes_;
  const auto it = quota_->reserved_by_owner_.find(owner_);
  if (it != quota_->reserved_by_owner_.end() && (it->second -= bytes_) == 0) quota_->reserved_by_owner_.erase(it);
}

std::uint64_t AssetQuota::stored_bytes() const {
  std::uint64_t total = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    // Published blobs only: an upload's temporary file is counted by its reservation.
    if (!is_sha256_hex(it->path().filename().string())) continue;
    std::error_code size_error;
    const std::uintmax_t size = it->file_size(size_error);
    if (!size_error) total += size;
  }
  return total;
}

AssetQuota::Reservation AssetQuota::reserve(std::uint64_t bytes, const std::string& owner) {
  if (limit_ == 0) return Reservation(nullptr, 0, {});
  const std::uint64_t stored = stored_bytes();
  std::lock_guard lock(mutex_);
  const std::uint64_t committed = stored + reserved_;
  if (committed > limit_ || bytes > limit_ - committed) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("asset of {} bytes: the scheduler's asset store holds {} bytes "
                                   "({} more being uploaded) of at most {} (--max-asset-store-bytes)",
                                   bytes, stored, reserved_, limit_));
  }
  const auto held = reserved_by_owner_.find(owner);
  const std::uint64_t owners = held == reserved_by_owner_.end() ? 0 : held->second;
  // An owner with nothing in flight may always start one upload (the limit above still holds).
  if (owners != 0 && (owners > owner_share() || bytes > owner_share() - owners)) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("asset of {} bytes: the uploads of '{}' in flight hold {} bytes of their share of "
                                   "{} (a quarter of --max-asset-store-bytes); finish or end them first",
                                   bytes, owner.empty() ? "anonymous" : owner, owners, owner_share()));
  }
  reserved_ += bytes;
  reserved_by_owner_[owner] += bytes;
  return Reservation(this, bytes, owner);
}

}  // namespace farm
