#pragma once
// An error a service reports with a specific gRPC status code (InputError is INVALID_ARGUMENT).
#include <grpcpp/support/status.h>

#include <stdexcept>
#include <string>

namespace farm {

class ServiceError : public std::runtime_error {
 public:
  ServiceError(grpc::StatusCode code, const std::string& message)
      : std::runtime_error(message), code_(code) {}
  grpc::StatusCode code() const { return code_; }
  grpc::Status status() const { return grpc::Status(code_, what()); }

 private:
  grpc::StatusCode code_;
};

}  // namespace farm

namespace farm {

// The status a service answers for the exception being handled (call only inside a catch
// block): ServiceError its own code, MissingAssetsError FAILED_PRECONDITION, InputError
// INVALID_ARGUMENT, DiskFull and bad_alloc RESOURCE_EXHAUSTED, anything else INTERNAL.
grpc::Status status_of_current_exception();

// "UNAVAILABLE", "DEADLINE_EXCEEDED", ...: the code as logs and messages name it; "ERROR" for
// codes the farm does not use.
const char* status_code_name(grpc::StatusCode code);

}  // namespace farm
