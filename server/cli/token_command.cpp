#include "server/cli/token_command.h"

#include <fmt/format.h>

#include <memory>
#include <string>

#include "server/common/access_roles.h"
#include "server/common/random_token.h"
#include "server/common/sha256.h"
#include "server/common/token_table.h"

namespace farm {
namespace {

struct TokenOptions {
  std::string name;
  std::string roles;
};

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
