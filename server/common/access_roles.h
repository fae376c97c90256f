#pragma once
// What a caller may do (issue #15): the roles a token carries. One role set per token; a request
// is allowed when the caller holds any role the RPC accepts (server/common/access_control.h).
//   submit     own jobs: submit (and upload their assets), get, watch, fetch, cancel
//   read       get, list and watch every job
//   admin      everything: other users' jobs, priorities above the scheduler's limit, assets
//   worker     RegisterWorker, Heartbeat, GetAsset of the jobs it was given
//   scheduler  a scheduler calling a worker's RenderTile
#include <cstdint>
#include <string>
#include <string_view>

namespace farm {

enum class Role : std::uint8_t { submit = 1, read = 2, admin = 4, worker = 8, scheduler = 16 };

// A set of roles, as a bit mask of Role values.
class Roles {
 public:
  constexpr Roles() = default;
  constexpr Roles(Role r) : bits_(static_cast<std::uint8_t>(r)) {}  // NOLINT: a role is a set of one
  static constexpr Roles all() { return Roles(0x1f); }

  constexpr Roles operator|(Roles o) const { return Roles(static_cast<std::uint8_t>(bits_ | o.bits_)); }
  constexpr bool has(Role r) const { return (bits_ & static_cast<std::uint8_t>(r)) != 0; }
  constexpr bool any_of(Roles o) const { return (bits_ & o.bits_) != 0; }
  constexpr bool empty() const { return bits_ == 0; }
  constexpr bool operator==(const Roles&) const = default;

 private:
  constexpr explicit Roles(std::uint8_t bits) : bits_(bits) {}
  std::uint8_t bits_ = 0;
};

constexpr Roles operator|(Role a, Role b) { return Roles(a) | Roles(b); }

// "submit", "read", ...; false when `name` is no role.
bool parse_role(std::string_view name, Role& role);
// "submit,read": the roles of a comma-separated list. InputError naming `where` and the first
// unknown role, or for an empty list.
Roles parse_roles(std::string_view list, std::string_view where);
// "submit,read" in the order of the enum.
std::string to_string(Roles roles);

}  // namespace farm
