#pragma once
// The security flags `farm scheduler` and `farm worker` share: --tokens, --tls-cert, --tls-key,
// --tls-ca, --insecure and --token-file (server/common/server_security.h).
#include <CLI/CLI.hpp>

#include "server/common/server_security.h"

namespace farm {

// `peers` names whom this server calls, for --token-file's help ("workers").
void add_server_security_flags(CLI::App& command, ServerSecurityOptions& options, const char* peers);

// Prints the warnings of `security` on stderr.
void print_security_warnings(const ServerSecurity& security);

}  // namespace farm
