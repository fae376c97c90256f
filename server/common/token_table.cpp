#include "server/common/token_table.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include "renderer/util/input_error.h"
#include "server/common/sha256.h"

namespace farm {
namespace {

constexpr std::size_t kMaxNameLength = 64;
constexpr std::size_t kMaxTokenFileBytes = 1 << 20;

// "weight=2.5" as 2500 thousandths, from 0.001 to 1000.
std::int64_t parse_share_weight(const std::string& text, const std::string& where) {
  const auto fail = [&] {
    throw InputError(fmt::format("{}: '{}': the fourth field is the owner's fair-share weight, weight=W with W "
                                 "from 0.001 to 1000 (default 1)",
                                 where, text.substr(0, 40)));
  };
  if (text.rfind("weight=", 0) != 0) fail();
  const std::string number = text.substr(7);
  char* end = nullptr;
  const double w = std::strtod(number.c_str(), &end);
  if (number.empty() || end != number.c_str() + number.size() || !(w >= 0.001 && w <= 1000)) fail();
  return static_cast<std::int64_t>(w * 1000 + 0.5);
}

}  // namespace

bool is_principal_name(std::string_view s) {
  if (s.empty() || s.size() > kMaxNameLength) return false;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-' || c == '@';
    if (!ok) return false;
  }
  return true;
}

bool well_formed_token(std::string_view token) {
  if (token.size() < 16 || token.size() > 512) return false;
  for (char c : token) {
    if (c <= ' ' || c > '~') return false;
  }
  return true;
}

TokenTable TokenTable::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(fmt::format("{}: cannot read the tokens file", file.string()));
  TokenTable table;
  std::set<std::string> names;
  std::string line;
  int number = 0;
  std::size_t bytes = 0;
  while (std::getline(in, line)) {
    ++number;
    bytes += line.size() + 1;
    if (bytes > kMaxTokenFileBytes) {
      throw InputError(fmt::format("{}: over {} bytes; is this a tokens file?", file.string(),
                                   kMaxTokenFileBytes));
    }
    if (const std::size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream fields(line);
    std::string digest, name, roles_text, weight_text, extra;
    if (!(fields >> digest)) continue;  // blank or comment
    const std::string where = fmt::format("{}:{}", file.string(), number);
    if (!(fields >> name >> roles_text) || ((fields >> weight_text) && (fields >> extra))) {
      throw InputError(fmt::format("{}: expected '<sha256 of the token> <name> <roles> [weight=W]'", where));
    }
    const std::int64_t weight_milli = weight_text.empty() ? kDefaultShareWeightMilli : parse_share_weight(weight_text, where);
    if (!is_sha256_hex(digest)) {
      throw InputError(fmt::format("{}: the first field must be the token's SHA-256 as 64 "
                                   "lowercase hex digits (the file never holds the token itself)",
                                   where));
    }
    if (!is_principal_name(name)) {
      throw InputError(fmt::format("{}: name '{}' must be 1 to {} of A-Z a-z 0-9 . _ - @", where,
                                   name.substr(0, 80), kMaxNameLength));
    }
    const Roles roles = parse_roles(roles_text, where);
    if (!names.insert(name).second) throw InputError(fmt::format("{}: name '{}' is listed twice", where, name));
    if (!table.by_hash_.emplace(digest, Principal{name, roles, weight_milli}).second) {
      throw InputError(fmt::format("{}: the same token is listed twice", where));
    }
  }
  if (table.by_hash_.empty()) throw InputError(fmt::format("{}: lists no tokens", file.string()));
  return table;
}

std::optional<Principal> TokenTable::find(std::string_view token) const {
  // Looked up by hash: the comparison never runs over the secret itself.
  const auto it = by_hash_.find(sha256_hex(token));
  if (it == by_hash_.end()) return std::nullopt;
  return it->second;
}

std::string read_client_token(const std::filesystem::path& token_file) {
  std::string token;
  std::string origin;
  if (!token_file.empty()) {
    std::ifstream in(token_file);
    if (!in) throw InputError(fmt::format("{}: cannot read the token file", token_file.string()));
    std::getline(in, token);
    origin = token_file.string();
  } else if (const char* env = std::getenv("FARM_TOKEN"); env != nullptr && *env != '\0') {
    token = env;
    origin = "FARM_TOKEN";
  } else {
    return {};
  }
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ' || token.back() == '\t')) {
    token.pop_back();
  }
  if (!well_formed_token(token)) {
    throw InputError(fmt::format("{}: not a farm token (16 to 512 printable characters, no spaces; "
                                 "`farm token` makes one)", origin));
  }
  return token;
}

}  // namespace farm
