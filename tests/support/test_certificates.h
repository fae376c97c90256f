#pragma once
// Certificates for TLS tests, made by the openssl command line in a test's folder: a CA, a node
// certificate it signed for 127.0.0.1 and localhost (server and client use), a client certificate
// (CN alice), and a second CA that signed nothing the servers trust.
#include <filesystem>
#include <string>

#include "server/common/tls_files.h"

namespace farm::test {

struct TestCertificates {
  std::filesystem::path ca, other_ca;
  TlsFiles node;      // cert + key, ca = ca
  TlsFiles client;    // CN alice, signed by ca; ca = ca
  TlsFiles stranger;  // CN mallory, signed by other_ca; ca = ca
  std::string problem;  // empty when every file was made
};

TestCertificates make_test_certificates(const std::filesystem::path& dir);

}  // namespace farm::test
