#include "server/cli/token_command.h"

#include <fmt/format.h>
#include <openssl/rand.h>

#include <array>
#include <memory>
#include <sstream>
#include <string>

#include "renderer/scene/input_error.h"
#include "server/common/access_roles.h"
#include "server/common/sha256.h"

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
  Roles roles;
  std::istringstream list(o.roles);
  for (std::string name; std::getline(list, name, ',');) {
    Role role{};
    if (!parse_role(name, role)) {
      throw InputError(fmt::format("--roles: unknown role '{}' (roles: submit, read, admin, worker, "
                                   "scheduler)", name));
    }
    roles = roles | role;
  }
  if (roles.empty()) throw InputError("--roles: give at least one role");
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
        if (name.empty() || name.size() > 64) return "1 to 64 characters";
        for (char c : name) {
          const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' ||
                          c == '-' || c == '@';
          if (!ok) return "only A-Z a-z 0-9 . _ - @";
        }
        return {};
      });
  token->add_option("--roles", o->roles,
                    "Comma-separated: submit (own jobs), read (every job), admin (everything), "
                    "worker (a farm worker), scheduler (a scheduler calling workers)")
      ->required();
  commands.add(token, [o] { return run_token(*o); });
}

}  // namespace farm
