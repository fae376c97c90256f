#include "server/scheduler/store/event_log.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace farm {

void EventLog::append_log(const v1::JobEvent& event, std::int64_t now_ms, bool essential, std::int64_t limit) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_, kRedoable);
  lock_job_locked(event.job().job_id());
  std::int64_t seq = 0, last = 0;
  {
    Query s(db_->prepared("SELECT j.seq, (SELECT MAX(n) FROM job_log l WHERE l.job_seq = j.seq) FROM jobs j "
                          "WHERE j.id = ?"));
    s.bind(1, event.job().job_id());
    if (!s.step()) return;  // deleted meanwhile
    seq = s.i64(0);
    last = s.is_null(1) ? 0 : s.i64(1);
  }
  if (last >= limit && !essential) return;
  Query(db_->prepared("INSERT INTO job_log (job_seq, n, at_ms, event) VALUES (?, ?, ?, ?)"))
      .bind(1, seq).bind(2, last + 1).bind(3, now_ms).bind_blob(4, event.SerializeAsString()).run();
  t.commit();
}

std::vector<v1::JobLogEntry> EventLog::job_log(const std::string& id, std::uint32_t after, int limit,
                                               bool* more) const {
  std::lock_guard lock(mutex_);
  Query s(db_->prepared("SELECT l.n, l.at_ms, l.event FROM job_log l JOIN jobs j ON l.job_seq = j.seq "
                        "WHERE j.id = ? AND l.n > ? ORDER BY l.n LIMIT ?"));
  s.bind(1, id).bind(2, static_cast<std::int64_t>(after)).bind(3, limit + 1);
  std::vector<v1::JobLogEntry> entries;
  if (more) *more = false;
  while (s.step()) {
    if (static_cast<int>(entries.size()) == limit) {
      if (more) *more = true;
      break;
    }
    v1::JobLogEntry& e = entries.emplace_back();
    e.set_number(static_cast<std::uint32_t>(s.i64(0)));
    *e.mutable_at() = timestamp(s.i64(1));
    e.mutable_event()->ParseFromString(s.blob(2));
  }
  return entries;
}

}  // namespace farm
