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
