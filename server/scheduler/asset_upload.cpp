#include "server/scheduler/asset_upload.h"

#include <fmt/format.h>

#include "renderer/util/input_error.h"
#include "server/common/sha256.h"
#include "server/common/service_error.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

bool AssetUpload::begin(const v1::AssetHeader& header) {
  if (!is_sha256_hex(header.sha256())) {
    throw InputError(fmt::format("UploadAsset: sha256 '{}' is not 64 lowercase hex digits",
                                 header.sha256().substr(0, 80)));
  }
  if (const std::uint64_t limit = core_->options().limits.max_asset_bytes; header.size() > limit) {
    throw ServiceError(grpc::StatusCode::RESOURCE_EXHAUSTED,
                       fmt::format("asset of {} bytes: at most {} (--max-asset-bytes)", header.size(), limit));
  }
  if (core_->assets().has(header.sha256())) return false;
  size_ = header.size();
  reserved_.emplace(core_->asset_quota().reserve(header.size(), owner_));
  writer_.emplace(core_->assets().begin(header.sha256(), header.size()));
  return true;
}

void AssetUpload::append(std::string_view bytes) {
  if (writer_->bytes_written() + bytes.size() > size_) {
    throw InputError(fmt::format("UploadAsset: more than the {} bytes the header announced", size_));
  }
  writer_->append(bytes);
}

void AssetUpload::commit() { writer_->commit(); }

}  // namespace farm
