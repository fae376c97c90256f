#pragma once
// A client of grpc.health.v1.Health/Check (proto/health.proto), the standard liveness call that
// both farm servers answer (server/common/health_service.h).
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

namespace farm {

struct HealthCheck {
  grpc::Status status;  // of the call itself
  int serving_status = 0;  // HealthCheckResponse.status: 1 SERVING, 2 NOT_SERVING, 0 unknown
  bool serving() const { return status.ok() && serving_status == 1; }
};

// Asks for the overall health (service ""), waiting until `deadline`. A process that accepts
// connections but does not answer (stopped, hung) gives DEADLINE_EXCEEDED.
HealthCheck check_health(const std::shared_ptr<grpc::Channel>& channel,
                         std::chrono::system_clock::time_point deadline);

}  // namespace farm
