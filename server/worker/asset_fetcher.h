#pragma once
// A worker's way to its schedulers' assets: Scheduler.GetAsset streams a blob by its SHA-256 into
// the local store, verified on the way in. A worker of several schedulers (`farm worker
// --scheduler A,B`) asks the one that sent the call first: it granted the job's assets to this
// worker for the call. The others are asked next (a scheduler away, or one of an older version
// that does not say who it is); every scheduler of one farm reads the same asset folder.
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/common/asset_store.h"
#include "server/common/client_identity.h"

namespace farm {

class AssetFetcher {
 public:
  // `identity`: the worker's token and TLS for the schedulers. At least one address.
  AssetFetcher(const std::vector<std::string>& scheduler_addresses, const ClientIdentity& identity);

  // The scheduler at `address` registered this worker and says it is `scheduler_id`.
  void learn(const std::string& scheduler_id, const std::string& address);

  // Downloads `ref` into `store`, from the scheduler `scheduler_id` (the call's) first when it is
  // known, then from the others in the order given; returns the address it came from.
  // ServiceError when none had it: FAILED_PRECONDITION when each that answered does not have it,
  // UNAVAILABLE when none could be reached or one refused, DATA_LOSS when the bytes did not match;
  // its message says what each scheduler answered.
  std::string fetch(const v1::AssetRef& ref, const AssetStore& store, const std::string& scheduler_id = {},
                    std::chrono::milliseconds timeout = std::chrono::minutes(5)) const;

  // "HOST:PORT", or the addresses joined by ", ".
  std::string describe() const;

 private:
  struct Source {
    std::string address;
    std::unique_ptr<v1::Scheduler::Stub> stub;
  };
  // One scheduler's try: ServiceError as fetch() says, of this scheduler alone.
  void fetch_from(const Source& source, const v1::AssetRef& ref, const AssetStore& store,
                  std::chrono::milliseconds timeout) const;

  std::vector<Source> sources_;
  mutable std::mutex mutex_;                   // guards learned_
  std::map<std::string, std::size_t> learned_;  // scheduler id -> index in sources_
};

}  // namespace farm
