#pragma once
// Where a client finds its scheduler and how it proves who it is: the address, the token and the
// TLS files, each from its flag, else its environment variable:
//   --scheduler HOST:PORT   FARM_SCHEDULER   (else localhost:50051)
//   --token-file FILE       FARM_TOKEN (the token itself)
//   --tls-ca FILE           FARM_TLS_CA      TLS, verifying the scheduler against this CA
//   --tls-cert/--tls-key    FARM_TLS_CERT / FARM_TLS_KEY   a client certificate (mTLS)
#include <filesystem>
#include <string>

#include "server/common/client_identity.h"

namespace farm {

inline constexpr const char* kDefaultSchedulerAddress = "localhost:50051";

struct SchedulerConnection {
  std::string address;
  ClientIdentity identity;
};

// What the command line said; empty fields fall back to the environment, then the defaults.
struct SchedulerConnectionFlags {
  std::string address;
  std::filesystem::path token_file;
  TlsFiles tls;
};

// InputError when the token file or FARM_TOKEN holds no well-formed token.
SchedulerConnection resolve_scheduler_connection(const SchedulerConnectionFlags& flags);

}  // namespace farm
