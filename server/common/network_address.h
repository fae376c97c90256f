#pragma once
// HOST:PORT addresses as the commands take them (--listen, --worker, --scheduler), in one place.
#include <optional>
#include <string>

namespace farm {

// "HOST" of "HOST:PORT" (an IPv6 literal keeps its brackets); the whole text when there is no port.
std::string host_of(const std::string& address);
// The port of "HOST:PORT"; nullopt when there is none or it is not a number from 0 to 65535.
std::optional<int> port_of(const std::string& address);

// Whether `address` (HOST:PORT, or a gRPC target such as dns:///HOST:PORT or ipv4:HOST:PORT)
// names this process's own server listening on `listen_host` and `port`: the same port, and a
// host that is the listen host, or any address of this machine's loopback when the server
// listens there or on every interface. A scheduler refuses to be its own worker by it.
bool names_own_server(const std::string& address, const std::string& listen_host, int port);

// Whether a worker at `address` runs on this machine: a loopback host (localhost, 127.x, ::1), or
// "in-process" (the embedded farm's worker). Its results are trusted as far as this machine is;
// another host's are spot-checked by default (SchedulerOptions::remote_verify_fraction).
bool on_this_host(const std::string& address);

// Why `address` cannot be a worker's address as a registering worker gives it (HOST:PORT: a DNS
// name or an IP literal, a port from 1 to 65535; no "unix:" socket, no scheme, at most 261
// bytes); empty when it can.
std::string worker_address_problem(const std::string& address);

}  // namespace farm
