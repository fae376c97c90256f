#pragma once
// The job store's jobs (job_store.h): a job's row inserted with its units, read, listed and
// counted, ended, paused, reprioritised, retried and deleted. Each method is one transaction.
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

class JobRecords : public StorePart {
 public:
  explicit JobRecords(StoreSession& session) : StorePart(session) {}

  // Inserts the job (QUEUED, or WAITING when it waits for other jobs), its dependencies and its
  // queued tiles, and enters its owner for fair share (owner_shares.h). Returns it as v1::Job.
  // DependencyError (nothing kept) when a dependency names no job.
  v1::Job add_job(const NewJob& job, std::int64_t now_ms);

  std::optional<v1::Job> get_job(const std::string& id) const;
  std::optional<v1::JobSpec> get_spec(const std::string& id) const;
  // The jobs that `filter` keeps, newest first, starting below submission order `before_seq`
  // (0 = newest). Returns the jobs and the seq to continue from (0 = no more).
  std::pair<std::vector<v1::Job>, std::int64_t> list_jobs(const JobFilter& filter, int limit,
                                                         std::int64_t before_seq) const;
  // Jobs QUEUED or RUNNING, in submission order.
  std::vector<std::string> active_jobs() const;

  // Final states. Each is a no-op (returns the job as it is) when the job is already final (and
  // finish_job when it is WAITING: release_waiting ends those), and
  // SUCCEEDED also when not every tile is done (quarantine_worker took some back) or not every
  // frame is merged.
  v1::Job finish_job(const std::string& id, v1::JobState state, const std::string& reason,
                     const std::string& validation, std::int64_t now_ms);
  v1::Job cancel_job(const std::string& id, std::int64_t now_ms);

  // Operator actions; each returns the job as it is now, nullopt when there is no such job.
  // A paused job keeps its state, and none of its units is claimed until it is resumed; only an
  // active job is paused or resumed (a final one is returned unchanged).
  std::optional<v1::Job> set_paused(const std::string& id, bool paused);
  std::optional<v1::Job> set_priority(const std::string& id, int priority);
  // The caps given replaced (0: none) on a job that has not ended (a final one is returned as is).
  std::optional<v1::Job> set_caps(const std::string& id, std::optional<int> max_workers,
                                  std::optional<int> max_units_in_flight);
  // A FAILED or CANCELLED job active again: its units not done queued with no attempt counted,
  // done units and merged frames kept, its claims dropped, its failure reason cleared, not paused.
  // RUNNING when some unit is done, else QUEUED. One transaction.
  std::optional<RetriedJob> retry_job(const std::string& id);
  // A final job and every row of it (tiles, frames, parts, claims, log) gone: true; false (and
  // nothing done) when the job is active. One transaction.
  std::optional<bool> delete_job(const std::string& id);
  // How many jobs are in each state (paused ones counted in theirs), how many of the active ones
  // are paused, and how many units wait in the queue of jobs that are not: the dashboard's /metrics.
  struct Counts {
    std::map<v1::JobState, std::int64_t> jobs;
    std::int64_t paused = 0;
    std::int64_t queued_units = 0;
  };
  Counts counts() const;
  // Final jobs that finished before `ms` (Unix ms), oldest first, at most `limit`.
  std::vector<std::string> finished_before(std::int64_t ms, int limit) const;
};

}  // namespace farm
