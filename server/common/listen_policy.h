#pragma once
// Secure by default: a server answers only its own machine unless its operator decides otherwise.
// Both `farm scheduler` and `farm worker` listen on loopback by default; beyond loopback they
// require authentication (tokens, or client certificates) unless --insecure is given.
#include <string>
#include <string_view>
#include <vector>

namespace farm {

inline constexpr const char* kDefaultSchedulerListen = "127.0.0.1:50051";
inline constexpr const char* kDefaultWorkerListen = "127.0.0.1:0";

// True for 127.0.0.0/8, ::1, localhost and unix sockets: addresses only this machine can reach.
bool is_loopback_listen(std::string_view listen);

struct ListenSecurity {
  std::string listen;
  bool tokens = false;               // --tokens given
  bool client_certificates = false;  // --tls-ca given (mTLS)
  bool tls = false;                  // --tls-cert given
  bool insecure = false;             // --insecure given
};

// InputError, saying what to do, for a non-loopback address without authentication and without
// --insecure. Returns warnings to print (tokens that would cross the network in plain text).
std::vector<std::string> check_listen_security(const ListenSecurity& s, std::string_view server);

}  // namespace farm
