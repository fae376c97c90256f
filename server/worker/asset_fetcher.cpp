#include "server/worker/asset_fetcher.h"

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include "renderer/scene/input_error.h"
#include "server/common/service_error.h"

namespace farm {

AssetFetcher::AssetFetcher(const std::string& scheduler_address, const ClientIdentity& identity)
    : address_(scheduler_address),
      stub_(v1::Scheduler::NewStub(open_channel(scheduler_address, identity))) {}

void AssetFetcher::fetch(const v1::AssetRef& ref, const AssetStore& store,
                         std::chrono::milliseconds timeout) const {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  v1::GetAssetRequest request;
  request.set_sha256(ref.sha256());
  AssetStore::Writer writer = store.begin(ref.sha256(), ref.size());
  auto reader = stub_->GetAsset(&context, request);
  v1::AssetChunk chunk;
  std::string bad;
  while (reader->Read(&chunk)) {
    if (!bad.empty()) continue;  // drain the stream so Finish() reports the call's own status
    if (chunk.offset() != writer.bytes_written()) {
      bad = fmt::format("chunk at offset {}, expected {}", chunk.offset(), writer.bytes_written());
      context.TryCancel();
      continue;
    }
    try {
      writer.append(chunk.data());
    } catch (const InputError& e) {
      bad = e.what();
      context.TryCancel();
    }
  }
  const grpc::Status status = reader->Finish();
  const std::string what = fmt::format("asset '{}' (sha256 {}) from scheduler {}", ref.path(),
                                       ref.sha256(), address_);
  if (!bad.empty()) throw ServiceError(grpc::StatusCode::DATA_LOSS, what + ": " + bad);
  if (!status.ok()) {
    const grpc::StatusCode code = status.error_code() == grpc::StatusCode::NOT_FOUND
                                      ? grpc::StatusCode::FAILED_PRECONDITION
                                      : grpc::StatusCode::UNAVAILABLE;
    throw ServiceError(code, fmt::format("cannot fetch {}: {}", what, status.error_message()));
  }
  try {
    writer.commit();
  } catch (const InputError& e) {
    throw ServiceError(grpc::StatusCode::DATA_LOSS, what + ": " + e.what());
  }
}

}  // namespace farm
