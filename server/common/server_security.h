#pragma once
// A server's security as its operator configured it (`farm scheduler` and `farm worker` share the
// flags): who may call it (--tokens), how it talks (--tls-cert, --tls-key, --tls-ca), where it
// may listen (--listen, --insecure), and how it calls the other servers of the farm (its own
// --token-file; TLS with the same certificate, presented as a client certificate, and CA).
#include <grpcpp/security/server_credentials.h>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/access_control.h"
#include "server/common/client_identity.h"
#include "server/common/tls_files.h"

namespace farm {

struct ServerSecurityOptions {
  std::filesystem::path tokens;      // tokens file; empty: no tokens needed
  TlsFiles tls;                      // the server's certificate, key, and the CA of its peers
  bool insecure = false;             // may listen beyond loopback without authentication
  std::filesystem::path token_file;  // this server's own token for the calls it makes
};

struct ServerSecurity {
  AccessControl access;
  std::shared_ptr<grpc::ServerCredentials> credentials;
  ClientIdentity outgoing;            // for calls to the farm's other servers
  std::vector<std::string> warnings;  // to print at start-up
};

// Reads and checks every file (InputError naming it) and applies the listen policy
// (listen_policy.h) to `listen`. `server` names the server in messages ("scheduler").
ServerSecurity make_server_security(const ServerSecurityOptions& options, const std::string& listen,
                                    std::string_view server);

}  // namespace farm
