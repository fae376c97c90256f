#pragma once
// The dashboard's logins: a browser that presented a valid token (POST /api/v1/login) gets a
// session id, a fresh random secret kept in an HttpOnly cookie, so the token itself is never
// stored by the browser nor sent again. A session lasts kLifetime; at most kMaxSessions live at
// once (the oldest goes first), so logins cannot grow the scheduler's memory without bound.
//
// Lock: DashboardSessions::mutex_ guards the map and is a leaf.
#include <chrono>
#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "server/common/token_table.h"

namespace farm {

class DashboardSessions {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr auto kLifetime = std::chrono::hours(12);
  static constexpr std::size_t kMaxSessions = 10000;

  // A new session for `who`; returns its id (64 hex digits).
  std::string open(const Principal& who, Clock::time_point now = Clock::now());
  // The session's holder, while it lasts.
  std::optional<Principal> find(const std::string& id, Clock::time_point now = Clock::now()) const;
  void close(const std::string& id);
  std::size_t size() const;

 private:
  struct Session {
    Principal who;
    Clock::time_point expires;
  };
  mutable std::mutex mutex_;
  std::map<std::string, Session> sessions_;
};

}  // namespace farm
