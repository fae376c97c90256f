#pragma once
// The bearer tokens a server accepts (`--tokens FILE`), each with a name and roles. The file holds
// no token itself, only its SHA-256, so reading it (or a leaked copy) gives no one access:
//
//   # <SHA-256 of the token, 64 hex digits>  <name>  <roles, comma-separated>
//   3f1c...e0  alice      submit
//   77ab...19  ci         submit,read
//   0d5e...4c  render-01  worker
//   9a2c...71  course-cg  submit  weight=4
//
// The optional fourth field is the owner's weight in fair share (default 1; docs/architecture.md,
// "Scheduling"): among jobs of equal priority, an owner of weight 4 gets four times the units of
// an owner of weight 1 while both have work queued.
//
// `farm token NAME --roles ROLES` makes a token and prints the line to add. Tokens are compared
// by their hashes, never logged, never echoed in an error.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/access_roles.h"

namespace farm {

// Who a request comes from once authenticated.
inline constexpr std::int64_t kDefaultShareWeightMilli = 1000;  // weight 1
struct Principal {
  std::string name;
  Roles roles;
  std::int64_t share_weight_milli = kDefaultShareWeightMilli;  // in thousandths
};

class TokenTable {
 public:
  // InputError naming the file and line for a malformed line, an unknown role, a repeated hash or
  // name, or a file with no tokens.
  static TokenTable load(const std::filesystem::path& file);

  // The token's holder; nullopt for a token the file does not list.
  std::optional<Principal> find(std::string_view token) const;
  std::size_t size() const { return by_hash_.size(); }

 private:
  std::map<std::string, Principal, std::less<>> by_hash_;
};

// A client's token, from `--token-file FILE` (its first line) or else $FARM_TOKEN; empty when
// neither is given. InputError when the file cannot be read or the token is malformed.
std::string read_client_token(const std::filesystem::path& token_file);

// True for a name a token may have: 1 to 64 of A-Z a-z 0-9 . _ - @ (jobs record it as their owner).
bool is_principal_name(std::string_view name);

// True for a token a client may send: 16 to 512 printable ASCII characters, no spaces.
bool well_formed_token(std::string_view token);

}  // namespace farm
