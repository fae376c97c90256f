#pragma once
// Who may call a server's RPCs: the check at the top of every handler of farm.v1.Scheduler and
// farm.v1.Worker. With `--tokens FILE` each call must carry `authorization: Bearer <token>`
// metadata naming a token of the file, and its roles must include one the RPC accepts. Without
// it every caller holds every role: the servers then listen only on loopback (listen_policy.h),
// or where the operator said --insecure, or behind mTLS (a verified client certificate, named by
// its common name).
#include <grpcpp/server_context.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/token_table.h"

namespace farm {

inline constexpr const char* kAnonymousCaller = "anonymous";

class AccessControl {
 public:
  AccessControl() = default;  // every caller holds every role
  explicit AccessControl(TokenTable tokens) : tokens_(std::make_shared<const TokenTable>(std::move(tokens))) {}

  bool requires_tokens() const { return tokens_ != nullptr; }

  // The caller of `context`. ServiceError UNAUTHENTICATED when tokens are required and the call
  // carries none, a malformed one, or one the file does not list (the token is never echoed).
  Principal authenticate(const grpc::ServerContext& context) const;

  // The same for a caller that is not gRPC's (the dashboard's HTTP requests): the bearer token it
  // presented, empty when none.
  Principal authenticate_token(std::string_view token) const;

  // authenticate(), then ServiceError PERMISSION_DENIED naming the caller and the RPC unless the
  // caller holds one of `allowed` (check()).
  Principal require(const grpc::ServerContext& context, Roles allowed, std::string_view rpc) const;
  static void check(const Principal& who, Roles allowed, std::string_view rpc);

 private:
  std::shared_ptr<const TokenTable> tokens_;
};

// ServiceError PERMISSION_DENIED: `who` may not `what`.
[[noreturn]] void deny(const Principal& who, std::string_view what);

}  // namespace farm
