#include "server/cli/server_security_flags.h"

#include <fmt/format.h>

#include <cstdio>

namespace farm {

void add_server_security_flags(CLI::App& command, ServerSecurityOptions& options, const char* peers) {
  command.add_option("--tokens", options.tokens,
                     "Require a bearer token on every call: FILE lists '<sha256 of token> <name> "
                     "<roles>' per line (roles submit, read, admin, worker, scheduler; `farm token` "
                     "makes tokens); calls without a listed token get UNAUTHENTICATED, calls "
                     "outside the token's roles PERMISSION_DENIED");
  command.add_option("--tls-cert", options.tls.cert,
                     "Serve TLS with this certificate (PEM, chain leaf first); also presented to "
                     "servers that ask for a client certificate");
  command.add_option("--tls-key", options.tls.key, "Private key of --tls-cert (PEM, unencrypted)");
  command.add_option("--tls-ca", options.tls.ca,
                     "CA certificates (PEM): require every client to present a certificate they "
                     "signed (mTLS), and verify the servers this one calls against them");
  command.add_flag("--insecure", options.insecure,
                   "Allow a --listen address beyond loopback without authentication (no --tokens, "
                   "no --tls-ca): anyone who reaches it may use it");
  command.add_option("--token-file", options.token_file,
                     fmt::format("File whose first line is this server's own token, sent on its "
                                 "calls to {}", peers));
}

void print_security_warnings(const ServerSecurity& security) {
  for (const std::string& w : security.warnings) fmt::print(stderr, "warning: {}\n", w);
  std::fflush(stderr);
}

}  // namespace farm
