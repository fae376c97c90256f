#pragma once
// The names the dashboard answers to. A page on another site whose DNS name is made to point at
// this machine (DNS rebinding) reaches the dashboard as a same-origin page of that name: its
// requests carry `Host: attacker.example`, and the Origin check, which compares Origin with
// Host, passes. So the Host header itself must name this server: the --http address, a loopback
// name (localhost, *.localhost), an IP address literal (no DNS name, so nothing to rebind), or a
// name the operator gave with --http-host.
#include <string>
#include <string_view>
#include <vector>

namespace farm {

class HostAllowlist {
 public:
  // `listen_host` is --http's host part (a wildcard such as 0.0.0.0 adds nothing); `names` are
  // the --http-host names, with or without a port, compared without case.
  HostAllowlist(std::string_view listen_host, const std::vector<std::string>& names);

  // Whether a request whose Host header is `host` (NAME, NAME:PORT, [V6]:PORT) is for this
  // server. An empty Host is not.
  bool allows(std::string_view host) const;

  // The names it allows beyond IP literals and loopback, for a refusal's message.
  std::string describe() const;

 private:
  std::vector<std::string> names_;  // lowercase, without port or brackets
};

// A Host header's name part: without the port and an IPv6 literal's brackets, lowercase.
std::string host_name_of(std::string_view host);

}  // namespace farm
