#pragma once
// A worker's membership of a scheduler's farm (docs/architecture.md, "Components": worker/):
// it registers itself (Scheduler.RegisterWorker) and heartbeats until it is destroyed; registers
// again when the scheduler forgot it (restarted), and retries while the scheduler is away. A
// scheduler without RegisterWorker (UNIMPLEMENTED) is left alone: assets are all it serves.
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>
#include <thread>

#include "proto/farm.grpc.pb.h"
#include "server/common/client_identity.h"

namespace farm {

class WorkerRegistration {
 public:
  // Starts registering `address` (where the scheduler reaches this worker) with `threads` render
  // threads and `tags`; `registered` is told the scheduler's id at each registration.
  WorkerRegistration(const std::string& scheduler, const ClientIdentity& identity, std::string address, int threads,
                     std::vector<std::string> tags, std::function<void(const std::string& scheduler_id)> registered);
  // Stops at once: a call in flight is cancelled rather than waited for to its deadline.
  ~WorkerRegistration();
  WorkerRegistration(const WorkerRegistration&) = delete;
  WorkerRegistration& operator=(const WorkerRegistration&) = delete;

 private:
  bool sleep(std::chrono::milliseconds d);  // false when stopped meanwhile
  void loop();

  std::string scheduler_, address_;
  int threads_;
  std::vector<std::string> tags_;
  std::function<void(const std::string&)> registered_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  grpc::ClientContext* call_ = nullptr;  // the call in flight, under mutex_
  std::thread thread_;
};

// Where a scheduler reaches a worker listening on `listen` at `port`: the listening host, or this
// machine's name when it listens on every interface.
std::string advertised_worker_address(const std::string& listen, int port);

}  // namespace farm
