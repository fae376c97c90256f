#include "tests/support/fake_scheduler.h"

#include <algorithm>
#include <chrono>

#include "server/common/sha256.h"

namespace farm::test {

namespace {
// Small, so that assets arrive in several chunks.
constexpr std::size_t kChunk = 4096;
}  // namespace

FakeScheduler::FakeScheduler() {
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&service_);
  server_ = builder.BuildAndStart();
  if (server_ && port != 0) address_ = "127.0.0.1:" + std::to_string(port);
}

FakeScheduler::~FakeScheduler() {
  if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
}

std::string FakeScheduler::add_asset(const std::string& bytes) {
  std::string sha = sha256_hex(bytes);
  std::lock_guard lock(service_.mutex);
  service_.blobs[sha] = bytes;
  return sha;
}

grpc::Status FakeScheduler::Service::GetAsset(grpc::ServerContext*,
                                              const v1::GetAssetRequest* request,
                                              grpc::ServerWriter<v1::AssetChunk>* writer) {
  ++calls;
  std::string bytes;
  {
    std::lock_guard lock(mutex);
    auto it = blobs.find(request->sha256());
    if (it == blobs.end()) return {grpc::StatusCode::NOT_FOUND, "no asset " + request->sha256()};
    bytes = it->second;
  }
  for (std::size_t offset = 0; offset == 0 || offset < bytes.size(); offset += kChunk) {
    v1::AssetChunk chunk;
    chunk.set_total_size(bytes.size());
    chunk.set_offset(offset);
    chunk.set_data(bytes.substr(offset, std::min(kChunk, bytes.size() - offset)));
    if (!writer->Write(chunk)) break;
  }
  return grpc::Status::OK;
}

}  // namespace farm::test
