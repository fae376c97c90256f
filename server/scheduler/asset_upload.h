#pragma once
// One asset uploaded through the front door (SchedulerFrontDoor::upload_asset: front_door.h, where
// who may upload is decided).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "proto/farm.pb.h"
#include "server/common/asset_store.h"
#include "server/scheduler/assets/asset_quota.h"

namespace farm {

class SchedulerCore;

// One asset uploaded by a caller the front door let upload (upload_asset): its header checked, its
// size reserved against the asset quota in the caller's name, its bytes written and hashed. The
// adapter reads the stream; an upload not committed leaves nothing behind.
class AssetUpload {
 public:
  // The upload's header. False when the store holds the asset already: nothing is written.
  // InputError for a sha256 that is not 64 lowercase hex digits; ServiceError RESOURCE_EXHAUSTED
  // past --max-asset-bytes or the quota (asset_quota.h).
  bool begin(const v1::AssetHeader& header);
  // InputError past the size the header announced; DiskFull when the disk has no room.
  void append(std::string_view bytes);
  // Publishes the blob. InputError when the bytes do not hash to the header's sha256.
  void commit();

 private:
  friend class SchedulerFrontDoor;
  AssetUpload(SchedulerCore& core, std::string owner) : core_(&core), owner_(std::move(owner)) {}

  SchedulerCore* core_;
  std::string owner_;
  std::uint64_t size_ = 0;  // as the header announced
  // In this order, so that the blob's temporary file goes before its reservation is freed.
  std::optional<AssetQuota::Reservation> reserved_;
  std::optional<AssetStore::Writer> writer_;
};

}  // namespace farm
