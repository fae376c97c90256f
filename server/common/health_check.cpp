#include "server/common/health_check.h"

#include "proto/health.grpc.pb.h"

namespace farm {

HealthCheck check_health(const std::shared_ptr<grpc::Channel>& channel,
                         std::chrono::system_clock::time_point deadline) {
  const auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(deadline);
  const grpc::health::v1::HealthCheckRequest request;  // service "": the server as a whole
  grpc::health::v1::HealthCheckResponse response;
  HealthCheck result;
  result.status = stub->Check(&context, request, &response);
  if (result.status.ok()) result.serving_status = response.status();
  return result;
}

}  // namespace farm
