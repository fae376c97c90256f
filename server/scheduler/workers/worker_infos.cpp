#include "server/scheduler/workers/worker_infos.h"

#include <google/protobuf/util/time_util.h>

namespace farm {

namespace {

google::protobuf::Timestamp timestamp_of(std::chrono::system_clock::time_point t) {
  return google::protobuf::util::TimeUtil::MillisecondsToTimestamp(
      std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count());
}

// What a worker said of itself and what it did, for an active and a lost one alike.
v1::WorkerInfo worker_info_of(const WorkerStatus& s) {
  v1::WorkerInfo w;
  w.set_worker_id(s.id);
  w.set_address(s.address);
  w.set_registered(s.registered);
  w.set_threads(s.facts.threads);
  for (const std::string& e : s.facts.engines) w.add_engines(e);
  for (const std::string& t : s.facts.tags) w.add_tags(t);
  w.set_hostname(s.facts.hostname);
  w.set_version(s.facts.version);
  w.set_units_done(s.units_done);
  w.set_units_failed(s.units_failed);
  if (s.registered) *w.mutable_last_heartbeat() = timestamp_of(s.last_heartbeat);
  *w.mutable_added_at() = timestamp_of(s.added_at);
  return w;
}

}  // namespace

std::vector<v1::WorkerInfo> worker_infos(const WorkerRegistry& registry, WorkerActivity activity) {
  std::vector<v1::WorkerInfo> out;
  for (const WorkerStatus& s : registry.workers()) {
    v1::WorkerInfo& w = out.emplace_back(worker_info_of(s));
    const bool backed_off = !s.up && s.backed_off_until > std::chrono::system_clock::now();
    w.set_state(s.quarantined  ? v1::WORKER_STATE_QUARANTINED
                : s.up         ? v1::WORKER_STATE_UP
                : backed_off   ? v1::WORKER_STATE_BACKED_OFF
                               : v1::WORKER_STATE_DOWN);
    if (backed_off) {
      *w.mutable_backed_off_until() = timestamp_of(s.backed_off_until);
      w.set_back_off_reason(s.back_off_reason);
    }
    for (std::string& job : activity.blocked_jobs(s.id)) w.add_blocked_jobs(std::move(job));
    w.set_quarantine_reason(s.quarantine_reason);
    for (std::string& c : activity.calls[s.id]) w.add_current(std::move(c));
  }
  // Gone, listed for a while with when and why: a worker killed mid-job does not just vanish.
  for (const WorkerStatus& s : registry.lost_workers()) {
    v1::WorkerInfo& w = out.emplace_back(worker_info_of(s));
    w.set_state(v1::WORKER_STATE_LOST);
    *w.mutable_lost_at() = timestamp_of(s.lost_at);
    w.set_lost_reason(s.lost_reason);
  }
  return out;
}

}  // namespace farm
