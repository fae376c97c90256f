#include "server/common/server_security.h"

#include "server/common/listen_policy.h"
#include "server/common/token_table.h"

namespace farm {

ServerSecurity make_server_security(const ServerSecurityOptions& options, const std::string& listen,
                                    std::string_view server) {
  ServerSecurity s;
  if (!options.tokens.empty()) s.access = AccessControl(TokenTable::load(options.tokens));
  s.credentials = server_credentials(options.tls);
  ListenSecurity policy;
  policy.listen = listen;
  policy.tokens = !options.tokens.empty();
  policy.client_certificates = !options.tls.ca.empty();
  policy.tls = options.tls.has_certificate();
  policy.insecure = options.insecure;
  s.warnings = check_listen_security(policy, server);
  // A farm talks TLS throughout or not at all: a TLS server calls its peers over TLS, verifying
  // them against the same CA and presenting its own certificate to those that ask for one.
  s.outgoing.tls = options.tls.has_certificate();
  if (s.outgoing.tls) s.outgoing.tls_files = options.tls;
  if (!options.token_file.empty()) s.outgoing.token = read_client_token(options.token_file);
  return s;
}

}  // namespace farm
