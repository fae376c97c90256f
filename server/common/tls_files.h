#pragma once
// TLS for the farm's gRPC services, from PEM files an operator gives (`--tls-cert`, `--tls-key`,
// `--tls-ca`). A server with a certificate serves TLS; with a CA as well it requires every client
// to present a certificate that CA signed (mTLS). A client verifies the server against the CA it
// is given (else the system's roots) and, given a certificate and key, presents them.
#include <grpcpp/security/credentials.h>
#include <grpcpp/security/server_credentials.h>

#include <filesystem>
#include <memory>
#include <string>

namespace farm {

struct TlsFiles {
  std::filesystem::path cert;  // PEM certificate chain, leaf first
  std::filesystem::path key;   // PEM private key of `cert`
  std::filesystem::path ca;    // PEM CA certificates: whom to trust

  bool has_certificate() const { return !cert.empty(); }
};

// Plain text without a certificate; TLS with one; mTLS (client certificates required and verified
// against `ca`) when `ca` is given too. InputError naming the file for a missing or unreadable
// file, a file that is no PEM certificate or key, a key that does not belong to the certificate,
// a key without a certificate or a certificate without a key.
std::shared_ptr<grpc::ServerCredentials> server_credentials(const TlsFiles& files);

// A client's credentials: TLS verifying the server against `ca` (the system's roots when empty),
// presenting `cert` and `key` when given. Same errors as server_credentials.
std::shared_ptr<grpc::ChannelCredentials> tls_channel_credentials(const TlsFiles& files);

}  // namespace farm
