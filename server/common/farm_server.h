#pragma once
// A started gRPC server with what every farm server serves beside its own service, set up in
// this one place for `farm scheduler` and `farm worker`: grpc.health.v1.Health (HealthService,
// answering for "" and the server's own service) and server reflection, which describes every
// service, health included, so grpcurl and other stock tools need no .proto file.
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "server/common/health_service.h"

namespace farm {

class FarmServer {
 public:
  // Adds health and reflection to `builder` (its own service already registered) and starts it.
  // `service`: the fully qualified name of the server's own service, which health answers for
  // (v1::Worker::service_full_name()). Null when the builder cannot start, as BuildAndStart.
  static std::unique_ptr<FarmServer> start(grpc::ServerBuilder& builder,
                                           const std::string& service);

  // grpc::Server's shutdown, health first: NOT_SERVING for Check, and every Watch call ends, so
  // that the grace period is spent on calls that do end by themselves.
  void Shutdown(std::chrono::system_clock::time_point deadline);
  void Wait() { server_->Wait(); }
  grpc::Server& server() { return *server_; }

  explicit FarmServer(const std::string& service);  // use start()
  ~FarmServer();  // ends Watch calls first: ~grpc::Server waits for every call without a deadline

 private:
  HealthService health_;  // outlives server_, which calls into it
  std::unique_ptr<grpc::Server> server_;
};

}  // namespace farm
