#pragma once
// The job store's dependencies (job_store.h; docs/architecture.md, "Scheduling"): a job submitted
// `after` others waits (WAITING) until each has SUCCEEDED, and fails naming the first that failed
// or was cancelled; `after_any` ones only have to end; `after_frames` holds each frame back until
// the other job has merged the same frame (the claim's part, UnitQueue). The rows: dependencies
// (job_seq, on_seq, any_end) and jobs.after_frames_seq. Each method is one transaction.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/store_part.h"

namespace farm {

// At most this many dependencies a job (after and after_any together).
inline constexpr std::size_t kMaxDependencies = 64;

class JobDependencies : public StorePart {
 public:
  explicit JobDependencies(StoreSession& session) : StorePart(session) {}

  // Sets the job's after, after_any, after_frames and dependents (the jobs that wait for it).
  void describe(v1::Job& job) const;

  // More jobs for a job that has not started to wait for: it is WAITING after this. nullopt: no
  // such job. DependencyError when an id names no job, when one waits (through any chain of
  // dependencies, frame-by-frame ones too) for this job (the cycle is named), or when the job has
  // started or ended.
  std::optional<v1::Job> add(const std::string& job_id, const std::vector<std::string>& after,
                             const std::vector<std::string>& after_any);

  // Settles every job its dependencies now decide, each by one caller however many schedulers
  // share the store: a WAITING job whose dependencies all ended as it needs is QUEUED (its owner
  // entering fair share as a new job's does); a WAITING job one of whose `after` jobs failed, was
  // cancelled or is gone, and an unfinished job whose `after_frames` job failed or was cancelled,
  // is FAILED naming it. Repeats until nothing changes (a failure runs down a chain), at most
  // `max_rounds` times. Returns the jobs it changed, in the order it changed them.
  std::vector<ReleasedJob> release_waiting(std::int64_t now_ms, int max_rounds = 64);
};

// For JobRecords::add_job, inside its transaction: the seqs of `ids`, DependencyError naming the
// first that names no job.
std::vector<std::int64_t> dependency_seqs(SqlConnection& db, const std::vector<std::string>& ids);
// The rows of `seq`'s dependencies on `on` (any_end: after_any's).
void insert_dependencies(SqlConnection& db, std::int64_t seq, const std::vector<std::int64_t>& on, bool any_end);

}  // namespace farm
