#include "tests/support/test_certificates.h"

#include "tests/support/run_command.h"

namespace farm::test {
namespace {

// Runs one openssl command in `dir`; appends its output to `problem` when it fails.
void openssl(const std::filesystem::path& dir, const std::string& args, std::string& problem) {
  if (!problem.empty()) return;
  const CommandResult r = run_command("cd " + shell_quote(dir.string()) + " && openssl " + args + " 2>&1");
  if (r.exit_code != 0) problem = "openssl " + args + ": " + r.output;
}

void make_ca(const std::filesystem::path& dir, const std::string& name, std::string& problem) {
  openssl(dir, "req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2 -keyout " +
                   name + ".key -out " + name + ".pem -subj /CN=" + name,
          problem);
}

// A key and a certificate `ca` signed, for `cn`, with the subjectAltName `san` when given.
void make_signed(const std::filesystem::path& dir, const std::string& name, const std::string& cn,
                 const std::string& ca, const std::string& san, std::string& problem) {
  std::string request = "req -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -keyout " + name +
                        ".key -out " + name + ".csr -subj /CN=" + cn;
  if (!san.empty()) request += " -addext subjectAltName=" + san;
  openssl(dir, request, problem);
  openssl(dir, "x509 -req -in " + name + ".csr -CA " + ca + ".pem -CAkey " + ca + ".key -CAcreateserial -days 2 -out " +
                   name + ".pem -copy_extensions copy",
          problem);
}

}  // namespace

TestCertificates make_test_certificates(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  TestCertificates c;
  make_ca(dir, "ca", c.problem);
  make_ca(dir, "other_ca", c.problem);
  make_signed(dir, "node", "node", "ca", "IP:127.0.0.1,DNS:localhost", c.problem);
  make_signed(dir, "client", "alice", "ca", "", c.problem);
  make_signed(dir, "stranger", "mallory", "other_ca", "", c.problem);
  c.ca = dir / "ca.pem";
  c.other_ca = dir / "other_ca.pem";
  c.node = {dir / "node.pem", dir / "node.key", c.ca};
  c.client = {dir / "client.pem", dir / "client.key", c.ca};
  c.stranger = {dir / "stranger.pem", dir / "stranger.key", c.ca};
  return c;
}

}  // namespace farm::test
