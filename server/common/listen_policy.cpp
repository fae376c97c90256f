#include "server/common/listen_policy.h"

#include <fmt/format.h>

#include "renderer/util/input_error.h"

namespace farm {

bool is_loopback_listen(std::string_view listen) {
  if (listen.starts_with("unix:") || listen.starts_with("unix-abstract:")) return true;
  std::string_view host = listen;
  if (host.starts_with("ipv4:")) host.remove_prefix(5);
  if (host.starts_with("ipv6:")) host.remove_prefix(5);
  if (host.starts_with("[")) {
    const std::size_t close = host.find(']');
    if (close == std::string_view::npos) return false;
    host = host.substr(1, close - 1);
  } else if (const std::size_t colon = host.rfind(':'); colon != std::string_view::npos) {
    host = host.substr(0, colon);
  }
  if (host == "localhost" || host == "::1") return true;
  // 127.0.0.0/8, written as four decimal parts.
  if (!host.starts_with("127.")) return false;
  int parts = 1;
  for (char c : host) {
    if (c == '.') ++parts;
    else if (c < '0' || c > '9') return false;
  }
  return parts == 4;
}

std::vector<std::string> check_listen_security(const ListenSecurity& s, std::string_view server) {
  std::vector<std::string> warnings;
  if (is_loopback_listen(s.listen)) return warnings;
  const bool authenticated = s.tokens || s.client_certificates;
  if (!authenticated && !s.insecure) {
    throw InputError(fmt::format(
        "{}: refusing to listen on {} without authentication: anyone who can reach it could use "
        "it. Give --tokens FILE (bearer tokens with roles; `farm token` makes them) and "
        "--tls-cert/--tls-key, or --tls-ca for client certificates (mTLS); listen on loopback "
        "(127.0.0.1:PORT); or, on a network you trust, add --insecure",
        server, s.listen));
  }
  if (!authenticated) {
    warnings.push_back(fmt::format("{}: --insecure: serving {} to anyone who can reach it, with "
                                   "no authentication", server, s.listen));
  } else if (!s.tls) {
    warnings.push_back(fmt::format("{}: tokens cross the network in plain text on {}; give "
                                   "--tls-cert and --tls-key", server, s.listen));
  }
  return warnings;
}

}  // namespace farm
