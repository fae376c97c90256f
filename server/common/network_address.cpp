#include "server/common/network_address.h"

#include <charconv>

namespace farm {

namespace {

// The host:port part of a gRPC target: "dns:///h:p", "ipv4:h:p", "ipv6:[h]:p" or plain "h:p".
std::string endpoint_of(const std::string& target) {
  for (const char* scheme : {"dns:///", "dns:", "ipv4:", "ipv6:"}) {
    const std::string s = scheme;
    if (target.rfind(s, 0) == 0) return target.substr(s.size());
  }
  return target;
}

bool is_loopback_host(const std::string& host) {
  return host == "localhost" || host == "[::1]" || host == "::1" || host.rfind("127.", 0) == 0;
}

bool is_wildcard_host(const std::string& host) {
  return host.empty() || host == "0.0.0.0" || host == "[::]" || host == "::";
}

}  // namespace

std::string host_of(const std::string& address) {
  const std::size_t colon = address.rfind(':');
  return colon == std::string::npos ? address : address.substr(0, colon);
}

std::optional<int> port_of(const std::string& address) {
  const std::size_t colon = address.rfind(':');
  if (colon == std::string::npos) return std::nullopt;
  int port = 0;
  const char* begin = address.data() + colon + 1;
  const char* end = address.data() + address.size();
  const auto [stop, error] = std::from_chars(begin, end, port);
  if (error != std::errc() || stop != end || begin == end || port < 0 || port > 65535) return std::nullopt;
  return port;
}

bool names_own_server(const std::string& address, const std::string& listen_host, int port) {
  const std::string endpoint = endpoint_of(address);
  if (port_of(endpoint) != port) return false;
  const std::string host = host_of(endpoint);
  if (host == listen_host) return true;
  // A server on every interface or on loopback is reached through any loopback name.
  return (is_wildcard_host(listen_host) || is_loopback_host(listen_host)) && is_loopback_host(host);
}

bool on_this_host(const std::string& address) {
  if (address == "in-process") return true;
  return is_loopback_host(host_of(endpoint_of(address)));
}

std::string worker_address_problem(const std::string& address) {
  if (address.empty()) return "the address is empty";
  if (address.size() > 261) return "the address is longer than 261 bytes";
  const std::optional<int> port = port_of(address);
  if (!port || *port == 0) return "give HOST:PORT with a port from 1 to 65535";
  std::string host = host_of(address);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
    for (char c : host) {
      const bool hex = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
      if (!hex && c != ':' && c != '.') return "the host is not an IPv6 address";
    }
    return {};
  }
  if (host.empty()) return "the host is empty";
  for (char c : host) {
    const bool name = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '-';
    if (!name) return "the host is not a DNS name or an IP address (a unix: socket or a URL is no worker address)";
  }
  return {};
}

}  // namespace farm
