#include "server/cli/token_command.h"

#include <fmt/format.h>
#include <openssl/rand.h>

#include <array>
#include <memory>
#include <string>

#include "server/common/access_roles.h"
#include "server/common/sha256.h"
#include "server/common/token_table.h"

namespace farm {
namespace {

struct TokenOptions {
  std::string name;
  std::string roles;
};

// 256 random bits from OpenSSL's CSPRNG, as 64 hex digits.
std::string random_token() {
  std::array<unsigned char, 32> bytes{};
  if (RAND_bytes(bytes.data(), static_cast<int>(bytes.size())) != 1) {
    throw std::runtime_error("no random bytes from OpenSSL");
  }
  std::string token;
  for (unsigned char b : bytes) token += fmt::format("{:02x}", b);
  return token;
}

int run_token(const TokenOptions& o) {
  const Roles roles = parse_roles(o.roles, "--roles");
  const std::string token = random_token();
  fmt::print("{}\n", token);
  fmt::print(stderr,
             "The token is on stdout; keep it secret (give it to '{}' as a --token-file, or in "
             "FARM_TOKEN). Add this line to the server's --tokens file:\n{} {} {}\n",
             o.name, sha256_hex(token), o.name, to_string(roles));
  return 0;
}

}  // namespace

void add_token_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<TokenOptions>();
  CLI::App* token = app.add_subcommand(
      "token", "Make a new bearer token: prints it, and the line for a server's --tokens file");
  token->add_option("NAME", o->name, "Who holds it (1-64 of A-Z a-z 0-9 . _ - @); jobs record it as their owner")
      ->required()
      ->check([](const std::string& name) -> std::string {
        return is_principal_name(name) ? "" : "1 to 64 of A-Z a-z 0-9 . _ - @";
      });
  token->add_option("--roles", o->roles,
                    "Comma-separated: submit (own jobs), read (every job), admin (everything), "
                    "worker (a farm worker), scheduler (a scheduler calling workers)")
      ->required();
  commands.add(token, [o] { return run_token(*o); });
}

}  // namespace farm
