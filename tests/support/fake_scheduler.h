#pragma once
// An in-process farm.v1.Scheduler that serves only GetAsset, from blobs a test adds: where a
// worker under test fetches the assets it lacks. Listens on a free port of 127.0.0.1.
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "proto/farm.grpc.pb.h"

namespace farm::test {

class FakeScheduler {
 public:
  FakeScheduler();
  ~FakeScheduler();

  const std::string& address() const { return address_; }
  // Serves `bytes` under their SHA-256, which it returns.
  std::string add_asset(const std::string& bytes);
  int get_asset_calls() const { return service_.calls; }

 private:
  struct Service final : v1::Scheduler::Service {
    grpc::Status GetAsset(grpc::ServerContext* context, const v1::GetAssetRequest* request,
                          grpc::ServerWriter<v1::AssetChunk>* writer) override;
    std::mutex mutex;
    std::map<std::string, std::string> blobs;
    std::atomic<int> calls{0};
  };

  Service service_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

}  // namespace farm::test
