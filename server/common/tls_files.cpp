#include "server/common/tls_files.h"

#include <fmt/format.h>
#include <openssl/bio.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include "renderer/util/input_error.h"
#include "server/common/read_whole_file.h"

namespace farm {
namespace {

constexpr std::uintmax_t kMaxPemBytes = 1 << 20;

std::string read_pem(const std::filesystem::path& file, const char* what) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (ec || !std::filesystem::is_regular_file(file)) {
    throw InputError(fmt::format("{}: cannot read the {} (not a readable file)", file.string(), what));
  }
  if (size > kMaxPemBytes) throw InputError(fmt::format("{}: over 1 MiB; not a {}", file.string(), what));
  return read_whole_file(file, what);
}

struct BioDeleter {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct X509Deleter {
  void operator()(X509* x) const { X509_free(x); }
};
struct KeyDeleter {
  void operator()(EVP_PKEY* k) const { EVP_PKEY_free(k); }
};

std::unique_ptr<BIO, BioDeleter> memory_bio(const std::string& text) {
  return std::unique_ptr<BIO, BioDeleter>(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

// The first certificate of `pem`; InputError naming `file` when there is none.
std::unique_ptr<X509, X509Deleter> first_certificate(const std::string& pem, const std::filesystem::path& file) {
  auto bio = memory_bio(pem);
  std::unique_ptr<X509, X509Deleter> cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) throw InputError(fmt::format("{}: no PEM certificate in it", file.string()));
  return cert;
}

struct PemFiles {
  std::string cert, key, ca;
};

// Reads and checks the files: each parses, and the key belongs to the certificate.
PemFiles load(const TlsFiles& files) {
  if (files.cert.empty() != files.key.empty()) {
    throw InputError(files.cert.empty() ? "--tls-key needs --tls-cert (the certificate of that key)"
                                        : "--tls-cert needs --tls-key (the certificate's private key)");
  }
  PemFiles pem;
  if (!files.cert.empty()) {
    pem.cert = read_pem(files.cert, "TLS certificate");
    pem.key = read_pem(files.key, "TLS private key");
    auto cert = first_certificate(pem.cert, files.cert);
    auto bio = memory_bio(pem.key);
    std::unique_ptr<EVP_PKEY, KeyDeleter> key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
    if (!key) throw InputError(fmt::format("{}: no unencrypted PEM private key in it", files.key.string()));
    if (X509_check_private_key(cert.get(), key.get()) != 1) {
      throw InputError(fmt::format("{}: this key does not belong to the certificate {}",
                                   files.key.string(), files.cert.string()));
    }
  }
  if (!files.ca.empty()) {
    pem.ca = read_pem(files.ca, "TLS CA certificate");
    first_certificate(pem.ca, files.ca);
  }
  return pem;
}

}  // namespace

std::shared_ptr<grpc::ServerCredentials> server_credentials(const TlsFiles& files) {
  if (!files.has_certificate()) {
    if (!files.ca.empty()) throw InputError("--tls-ca needs --tls-cert and --tls-key (the server's own certificate)");
    return grpc::InsecureServerCredentials();
  }
  PemFiles pem = load(files);
  grpc::SslServerCredentialsOptions options(
      pem.ca.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                     : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_root_certs = pem.ca;
  options.pem_key_cert_pairs.push_back({pem.key, pem.cert});
  return grpc::SslServerCredentials(options);
}

std::shared_ptr<grpc::ChannelCredentials> tls_channel_credentials(const TlsFiles& files) {
  PemFiles pem = load(files);
  grpc::SslCredentialsOptions options;
  options.pem_root_certs = pem.ca;
  options.pem_private_key = pem.key;
  options.pem_cert_chain = pem.cert;
  return grpc::SslCredentials(options);
}

}  // namespace farm
