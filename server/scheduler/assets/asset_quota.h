#pragma once
// The asset store's total size, held under --max-asset-store-bytes. Uploads are content-addressed
// and kept, so without a bound a client could fill the scheduler's disk one distinct blob at a
// time. An upload reserves the size its header announces before its first byte is written; the
// reservation ends when the upload does (committed, the blob now counts on disk; or not).
// One owner's uploads in flight may hold at most a quarter of the limit (issue #32: 40 idle
// streams announcing 2 GiB each held all of it), so that nobody can keep the others out alone;
// an owner with none in flight may always start one.
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>

namespace farm {

class AssetQuota {
 public:
  // `limit` 0: no limit.
  AssetQuota(std::filesystem::path store_dir, std::uint64_t limit);

  class Reservation {
   public:
    Reservation(Reservation&& other) noexcept;
    Reservation& operator=(Reservation&&) = delete;
    Reservation(const Reservation&) = delete;
    ~Reservation();

   private:
    friend class AssetQuota;
    Reservation(AssetQuota* quota, std::uint64_t bytes, std::string owner)
        : quota_(quota), bytes_(bytes), owner_(std::move(owner)) {}
    AssetQuota* quota_;
    std::uint64_t bytes_;
    std::string owner_;
  };

  // ServiceError RESOURCE_EXHAUSTED naming the store's size, the limit and its flag when the
  // blobs stored plus the uploads in flight plus `bytes` would pass the limit, or when `owner`'s
  // uploads in flight plus `bytes` would pass its share (owner_share()).
  Reservation reserve(std::uint64_t bytes, const std::string& owner = {});
  // What one owner's uploads in flight may hold: a quarter of the limit.
  std::uint64_t owner_share() const { return limit_ / 4; }

  // What the published blobs take on disk now (the store is read each time: blobs removed as
  // damaged, or by an operator, count no more).
  std::uint64_t stored_bytes() const;

 private:
  std::filesystem::path dir_;
  std::uint64_t limit_;
  std::mutex mutex_;
  std::uint64_t reserved_ = 0;  // uploads in flight, guarded by mutex_
  std::map<std::string, std::uint64_t> reserved_by_owner_;  // likewise, by owner
};

}  // namespace farm
