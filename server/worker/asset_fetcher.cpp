#include "server/worker/asset_fetcher.h"

#include <fmt/format.h>
#include <grpcpp/grpcpp.h>

#include <numeric>
#include <stdexcept>

#include "renderer/util/input_error.h"
#include "server/common/service_error.h"

namespace farm {

AssetFetcher::AssetFetcher(const std::vector<std::string>& scheduler_addresses, const ClientIdentity& identity) {
  if (scheduler_addresses.empty()) throw std::invalid_argument("AssetFetcher: no scheduler");
  for (const std::string& address : scheduler_addresses) {
    sources_.push_back({address, v1::Scheduler::NewStub(open_channel(address, identity))});
  }
}

void AssetFetcher::learn(const std::string& scheduler_id, const std::string& address) {
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    if (sources_[i].address != address) continue;
    std::lock_guard lock(mutex_);
    learned_[scheduler_id] = i;
    return;
  }
}

std::string AssetFetcher::describe() const {
  std::string out;
  for (const Source& s : sources_) out += (out.empty() ? "" : ", ") + s.address;
  return out;
}

std::string AssetFetcher::fetch(const v1::AssetRef& ref, const AssetStore& store, const std::string& scheduler_id,
                                std::chrono::milliseconds timeout) const {
  std::vector<std::size_t> order(sources_.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  {
    std::lock_guard lock(mutex_);
    if (auto it = learned_.find(scheduler_id); it != learned_.end()) {
      order.erase(order.begin() + static_cast<std::ptrdiff_t>(it->second));
      order.insert(order.begin(), it->second);
    }
  }
  std::string answers;
  bool only_missing = true;
  grpc::StatusCode last = grpc::StatusCode::UNAVAILABLE;
  for (std::size_t i : order) {
    try {
      fetch_from(sources_[i], ref, store, timeout);
      return sources_[i].address;
    } catch (const ServiceError& e) {
      if (sources_.size() == 1) throw;
      answers += fmt::format("{}{}", answers.empty() ? "" : "; ", e.what());
      only_missing &= e.code() == grpc::StatusCode::FAILED_PRECONDITION;
      last = e.code();
    }
  }
  throw ServiceError(only_missing ? grpc::StatusCode::FAILED_PRECONDITION
                     : last == grpc::StatusCode::DATA_LOSS ? grpc::StatusCode::DATA_LOSS
                                                           : grpc::StatusCode::UNAVAILABLE,
                     fmt::format("no scheduler gave asset '{}': {}", ref.path(), answers));
}

void AssetFetcher::fetch_from(const Source& source, const v1::AssetRef& ref, const AssetStore& store,
                              std::chrono::milliseconds timeout) const {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  v1::GetAssetRequest request;
  request.set_sha256(ref.sha256());
  AssetStore::Writer writer = store.begin(ref.sha256(), ref.size());
  auto reader = source.stub->GetAsset(&context, request);
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
                                       ref.sha256(), source.address);
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
