#include "server/scheduler/http/host_allowlist.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>

namespace farm {

namespace {

bool is_ip_literal(const std::string& name) {
  unsigned char buffer[16];
  return inet_pton(AF_INET, name.c_str(), buffer) == 1 || inet_pton(AF_INET6, name.c_str(), buffer) == 1;
}

bool is_loopback_name(const std::string& name) {
  constexpr std::string_view kLocal = "localhost";
  if (name == kLocal) return true;
  // RFC 6761: every name under .localhost is this machine.
  return name.size() > kLocal.size() + 1 && name.ends_with(".localhost");
}

bool is_wildcard(const std::string& name) { return name.empty() || name == "0.0.0.0" || name == "::"; }

}  // namespace

std::string host_name_of(std::string_view host) {
  std::string name;
  if (!host.empty() && host.front() == '[') {
    const std::size_t close = host.find(']');
    name = std::string(host.substr(1, close == std::string_view::npos ? std::string_view::npos : close - 1));
  } else {
    const std::size_t colon = host.find(':');
    // Two colons without brackets: a bare IPv6 literal (not valid in Host, but no port to cut).
    name = std::string(colon != std::string_view::npos && host.find(':', colon + 1) == std::string_view::npos
                           ? host.substr(0, colon)
                           : host);
  }
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  if (!name.empty() && name.back() == '.') name.pop_back();  // "localhost." is "localhost"
  return name;
}

HostAllowlist::HostAllowlist(std::string_view listen_host, const std::vector<std::string>& names) {
  const std::string listen = host_name_of(listen_host);
  if (!is_wildcard(listen)) names_.push_back(listen);
  for (const std::string& n : names) names_.push_back(host_name_of(n));
}

bool HostAllowlist::allows(std::string_view host) const {
  const std::string name = host_name_of(host);
  if (name.empty()) return false;
  if (is_ip_literal(name) || is_loopback_name(name)) return true;
  return std::find(names_.begin(), names_.end(), name) != names_.end();
}

std::string HostAllowlist::describe() const {
  std::string text = "an IP address, localhost";
  for (const std::string& n : names_) text += ", " + n;
  return text;
}

}  // namespace farm
