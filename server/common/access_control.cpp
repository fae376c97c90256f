#include "server/common/access_control.h"

#include <fmt/format.h>

#include <cctype>

#include "server/common/service_error.h"

namespace farm {
namespace {

constexpr std::string_view kBearer = "bearer ";

bool starts_with_ignoring_case(std::string_view text, std::string_view prefix) {
  if (text.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(text[i])) != prefix[i]) return false;
  }
  return true;
}

// The verified client certificate's common name, when the call came over mTLS.
std::string certificate_name(const grpc::ServerContext& context) {
  const std::shared_ptr<const grpc::AuthContext> auth = context.auth_context();
  if (!auth || !auth->IsPeerAuthenticated()) return {};
  for (const grpc::string_ref& name : auth->FindPropertyValues("x509_common_name")) {
    return std::string(name.data(), name.size());
  }
  return {};
}

[[noreturn]] void unauthenticated(std::string_view why) {
  throw ServiceError(grpc::StatusCode::UNAUTHENTICATED,
                     fmt::format("{}: this server needs 'authorization: Bearer <token>' with a "
                                 "token from its tokens file (farm: --token-file FILE or FARM_TOKEN)",
                                 why));
}

}  // namespace

Principal AccessControl::authenticate(const grpc::ServerContext& context) const {
  if (!tokens_) {
    std::string name = certificate_name(context);
    return Principal{name.empty() ? kAnonymousCaller : std::move(name), Roles::all()};
  }
  const auto& metadata = context.client_metadata();
  const auto [first, last] = metadata.equal_range("authorization");
  if (first == last) unauthenticated("no token");
  if (std::next(first) != last) unauthenticated("more than one authorization header");
  const std::string_view value(first->second.data(), first->second.size());
  if (!starts_with_ignoring_case(value, kBearer)) unauthenticated("not a bearer token");
  return authenticate_token(value.substr(kBearer.size()));
}

Principal AccessControl::authenticate_token(std::string_view token) const {
  if (!tokens_) return Principal{kAnonymousCaller, Roles::all()};
  if (token.empty()) unauthenticated("no token");
  if (!well_formed_token(token)) unauthenticated("malformed token");
  std::optional<Principal> who = tokens_->find(token);
  if (!who) unauthenticated("unknown token");
  return std::move(*who);
}

Principal AccessControl::require(const grpc::ServerContext& context, Roles allowed,
                                 std::string_view rpc) const {
  Principal who = authenticate(context);
  check(who, allowed, rpc);
  return who;
}

void AccessControl::check(const Principal& who, Roles allowed, std::string_view rpc) {
  if (!who.roles.any_of(allowed)) deny(who, fmt::format("call {} (it needs a role of: {})", rpc, to_string(allowed)));
}

void deny(const Principal& who, std::string_view what) {
  throw ServiceError(grpc::StatusCode::PERMISSION_DENIED,
                     fmt::format("'{}' (roles: {}) may not {}", who.name, to_string(who.roles), what));
}

}  // namespace farm
