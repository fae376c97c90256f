#include "server/common/access_roles.h"

#include <fmt/format.h>

#include <array>
#include <utility>

#include "renderer/util/input_error.h"

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

Roles parse_roles(std::string_view list, std::string_view where) {
  Roles roles;
  while (true) {
    const std::size_t comma = list.find(',');
    const std::string_view name = list.substr(0, comma);
    Role role{};
    if (!parse_role(name, role)) {
      throw InputError(fmt::format("{}: unknown role '{}' (roles: submit, read, admin, worker, scheduler)",
                                   where, name.substr(0, 40)));
    }
    roles = roles | role;
    if (comma == std::string_view::npos) return roles;
    list.remove_prefix(comma + 1);
  }
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
