#include "server/common/access_roles.h"

#include <array>
#include <utility>

namespace farm {
namespace {

constexpr std::array<std::pair<std::string_view, Role>, 5> kRoleNames{{
    {"submit", Role::submit},
    {"read", Role::read},
    {"admin", Role::admin},
    {"worker", Role::worker},
    {"scheduler", Role::scheduler},
}};

}  // namespace

bool parse_role(std::string_view name, Role& role) {
  for (const auto& [text, value] : kRoleNames) {
    if (text == name) {
      role = value;
      return true;
    }
  }
  return false;
}

std::string to_string(Roles roles) {
  std::string out;
  for (const auto& [text, value] : kRoleNames) {
    if (!roles.has(value)) continue;
    if (!out.empty()) out += ',';
    out += text;
  }
  return out;
}

}  // namespace farm
