#pragma once
// A worker's way to the scheduler's assets: Scheduler.GetAsset streams a blob by its SHA-256 into
// the local store, verified on the way in.
#include <chrono>
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/asset_store.h"
#include "server/common/client_identity.h"

namespace farm {

class AssetFetcher {
 public:
  // `identity`: the worker's token and TLS for the scheduler.
  AssetFetcher(const std::string& scheduler_address, const ClientIdentity& identity);

  // Downloads `ref` into `store`. ServiceError: FAILED_PRECONDITION when the scheduler does not
  // have it, UNAVAILABLE when it cannot be reached, DATA_LOSS when the bytes do not match.
  void fetch(const v1::AssetRef& ref, const AssetStore& store,
             std::chrono::milliseconds timeout = std::chrono::minutes(5)) const;

  const std::string& address() const { return address_; }

 private:
  std::string address_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
};

}  // namespace farm
