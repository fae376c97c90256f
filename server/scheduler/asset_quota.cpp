#include "server/scheduler/asset_quota.h"

#include <fmt/format.h>

#include <system_error>
#include <utility>

#include "server/common/service_error.h"
#include "server/common/sha256.h"

namespace farm {

namespace fs = std::filesystem;

AssetQuota::AssetQuota(fs::path store_dir, std::uint64_t limit) : dir_(std::move(store_dir)), limit_(limit) {}

AssetQuota::Reservation::Reservation(Reservation&& other) noexcept
    : quota_(std::exchange(other.quota_, nullptr)), bytes_(other.bytes_) {}

AssetQuota::Reservation::~Reservation() {
  if (!quota_) return;
  std::lock_guard lock(quota_->mutex_);
  quota_->reserved_ -= bytes_;
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

AssetQuota::Reservation AssetQuota::reserve(std::uint64_t bytes) {
  if (limit_ == 0) return Reservation(nullptr, 0);
  const std::uint64_t stored = stored_bytes();
  std::lock_guard lock(mutex_);
  const std::uint64_t committed = stored + reserved_;
  if (committed > limit_ || bytes > limit_ - committed) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("asset of {} bytes: the scheduler's asset store holds {} bytes "
                                   "({} more being uploaded) of at most {} (--max-asset-store-bytes)",
                                   bytes, stored, reserved_, limit_));
  }
  reserved_ += bytes;
  return Reservation(this, bytes);
}

}  // namespace farm
