#include "server/scheduler/store/scheduler_leases.h"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace farm {

void SchedulerLeases::set_scheduler(const std::string& id) {
  std::lock_guard lock(mutex_);
  scheduler_ = id;
}

void SchedulerLeases::hold_lease(std::int64_t until_ms) {
  std::lock_guard lock(mutex_);
  Query(db_->prepared("INSERT INTO schedulers (id, lease_until_ms) VALUES (?, ?) "
                      "ON CONFLICT (id) DO UPDATE SET lease_until_ms = excluded.lease_until_ms"))
      .bind(1, scheduler_).bind(2, until_ms).run();
}

void SchedulerLeases::drop_lease() {
  std::lock_guard lock(mutex_);
  Query(db_->prepared("DELETE FROM schedulers WHERE id = ?")).bind(1, scheduler_).run();
}

std::vector<ReapedScheduler> SchedulerLeases::reap_expired(std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  SqlTransaction t(*db_);
  std::vector<ReapedScheduler> reaped;
  {
    // Locked, so that two schedulers reaping at once take each lease once.
    const std::string lock_rows = db_->dialect() == SqlDialect::PostgreSQL ? " FOR UPDATE SKIP LOCKED" : "";
    Query s(db_->prepared("SELECT id FROM schedulers WHERE lease_until_ms < ? AND id <> ? ORDER BY id" + lock_rows));
    s.bind(1, now_ms).bind(2, scheduler_);
    while (s.step()) reaped.push_back({s.text(0), 0});
  }
  for (ReapedScheduler& r : reaped) {
    lock_jobs_of_tiles_locked("state = 1 AND scheduler = ?", r.id);  // its running tiles' jobs
    // Not the tiles' fault: no attempt counted.
    Query requeue(db_->prepared("UPDATE tiles SET state = 0, worker = '', scheduler = '' WHERE state = 1 AND scheduler = ?"));
    requeue.bind(1, r.id).run();
    r.tiles_queued_again = requeue.changes();
    Query(db_->prepared("DELETE FROM claims WHERE scheduler = ?")).bind(1, r.id).run();
    Query(db_->prepared("DELETE FROM schedulers WHERE id = ?")).bind(1, r.id).run();
  }
  t.commit();
  return reaped;
}

bool SchedulerLeases::claim_locked(const std::string& job_id, const std::string& what) {
  SqlTransaction t(*db_, kRedoable);
  lock_job_locked(job_id);
  Query(db_->prepared("INSERT INTO claims (job_seq, what, scheduler) SELECT seq, ?, ? FROM jobs WHERE id = ? "
                      "ON CONFLICT (job_seq, what) DO NOTHING"))
      .bind(1, what).bind(2, scheduler_).bind(3, job_id).run();
  Query s(db_->prepared("SELECT c.scheduler FROM claims c JOIN jobs j ON c.job_seq = j.seq WHERE j.id = ? AND c.what = ?"));
  s.bind(1, job_id).bind(2, what);
  const bool mine = s.step() && s.text(0) == scheduler_;
  s.reset();
  t.commit();
  return mine;
}

bool SchedulerLeases::claim_frame_merge(const std::string& job_id, int frame) {
  std::lock_guard lock(mutex_);
  return claim_locked(job_id, fmt::format("frame {}", frame));
}

bool SchedulerLeases::claim_job_end(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  return claim_locked(job_id, "end");
}

}  // namespace farm
