#include "server/scheduler/http/dashboard_sessions.h"

#include <algorithm>

#include "server/common/random_token.h"

namespace farm {

std::string DashboardSessions::open(const Principal& who, Clock::time_point now) {
  std::string id = random_token();
  std::lock_guard lock(mutex_);
  std::erase_if(sessions_, [&](const auto& s) { return s.second.expires <= now; });
  if (sessions_.size() >= kMaxSessions) {
    sessions_.erase(std::min_element(sessions_.begin(), sessions_.end(), [](const auto& a, const auto& b) {
      return a.second.expires < b.second.expires;
    }));
  }
  sessions_[id] = Session{who, now + kLifetime};
  return id;
}

std::optional<Principal> DashboardSessions::find(const std::string& id, Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  const auto it = sessions_.find(id);
  if (it == sessions_.end() || it->second.expires <= now) return std::nullopt;
  return it->second.who;
}

void DashboardSessions::close(const std::string& id) {
  std::lock_guard lock(mutex_);
  sessions_.erase(id);
}

std::size_t DashboardSessions::size() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

}  // namespace farm
