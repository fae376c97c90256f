#pragma once
// The job store's event log (job_store.h): each job's events, numbered from 1, kept up to a limit
// past which only the essential ones are (farm log, the dashboard's history).
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/store_part.h"

namespace farm {

class EventLog : public StorePart {
 public:
  explicit EventLog(StoreSession& session) : StorePart(session) {}

  // The job's event log: `event` (its job the job then) appended as the next entry, at `now_ms`.
  // Past `limit` entries only an `essential` event is kept. Nothing for a job that is gone.
  void append_log(const v1::JobEvent& event, std::int64_t now_ms, bool essential,
                  std::int64_t limit = kMaxLogEntries);
  // Entries numbered above `after`, in order, at most `limit`; `more` says whether others follow.
  std::vector<v1::JobLogEntry> job_log(const std::string& id, std::uint32_t after, int limit,
                                       bool* more = nullptr) const;
};

}  // namespace farm
