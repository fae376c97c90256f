#pragma once
// grpc.health.v1.Health (proto/health.proto) as the farm's servers serve it. The server as a
// whole ("") and the services it was made for are SERVING from the start until shutdown(), when
// they turn NOT_SERVING for good and every Watch ends. Other names are unknown: Check answers
// NOT_FOUND and Watch SERVICE_UNKNOWN (the call stays open), as the spec says.
//
// Ours rather than grpc::EnableDefaultHealthCheckService: gRPC's default service is not in the
// generated descriptor pool, so server reflection could not describe it and grpcurl could call
// it only when handed a health.proto. This one is compiled from proto/health.proto like farm.proto.
#include <grpcpp/grpcpp.h>

#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "proto/health.grpc.pb.h"

namespace farm {

class HealthService final : public grpc::health::v1::Health::CallbackService {
 public:
  using Request = grpc::health::v1::HealthCheckRequest;
  using Response = grpc::health::v1::HealthCheckResponse;

  // `services`: the fully qualified names answered besides "" (e.g. "farm.v1.Worker").
  // Must outlive the grpc::Server it is registered with, like every service.
  explicit HealthService(std::vector<std::string> services);

  // Everything NOT_SERVING from now on; each Watch sends that, then ends with UNAVAILABLE, and a
  // Watch begun later does the same. Call it before grpc::Server::Shutdown, whose grace period
  // would otherwise be spent waiting for Watch calls that never end by themselves.
  void shutdown();

  grpc::ServerUnaryReactor* Check(grpc::CallbackServerContext* context, const Request* request,
                                  Response* response) override;
  grpc::ServerWriteReactor<Response>* Watch(grpc::CallbackServerContext* context,
                                            const Request* request) override;

 private:
  class Watcher;
  enum class Step { None, Write, Finish };

  Response::ServingStatus status_of(const std::string& service) const;  // with mutex_ held
  Step next_step(Watcher& watcher);                                     // with mutex_ held
  static void take(Watcher& watcher, Step step);                        // without mutex_
  // A Watcher's events, each of them: update its state, then take the step it leads to.
  void write_done(Watcher& watcher, bool ok);
  void cancelled(Watcher& watcher);
  void done(Watcher& watcher);

  const std::vector<std::string> services_;
  std::mutex mutex_;
  bool shut_down_ = false;
  std::set<Watcher*> watchers_;
};

}  // namespace farm
