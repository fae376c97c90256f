#pragma once
// What the farm learns from units failing on workers (issue #32), as Deadline's and Flamenco's
// per-job blocklists do: one bad worker never fails the farm's jobs, and one bad job never takes
// a worker out of the farm.
//
// - A unit's attempt is charged (UnitQueue::batch_failed) only when the failure may be the unit's
//   own: the first failure of a worker in a job, and only while the worker is not failing across
//   jobs. A worker that fails whatever it is given (a broken install, a scheduler listed as its
//   own worker) charges at most one attempt, in the first job it fails; its other failures put
//   the units back uncharged. So a job fails on its attempts only when workers that otherwise
//   succeed fail its units.
// - A worker that fails `block_after` units of one job (at once, when it says the unit can never
//   render: INVALID_ARGUMENT) is kept off that job: its slots claim other jobs' units.
// - A worker whose failures span several jobs in a row, or that refuses calls (the call is not
//   the unit's fault), is backed off: it gets nothing for `back_off_first`, doubling with each
//   further failure up to `back_off_max`, and its first success resets it all.
//
// Per scheduler, in memory: a restarted scheduler starts every worker afresh. Lock: one mutex of
// its own, taken with nothing else held inside it (a leaf: the dispatcher calls it under its own
// lock and the store's, as claim_next_batch's filter).
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace farm {

enum class FailureKind {
  Unit,           // the call failed (INTERNAL...): the unit or the worker, not known which
  NeverRenders,   // the worker says this unit can never render (INVALID_ARGUMENT)
  Refused,        // the worker refused the call (UNIMPLEMENTED, PERMISSION_DENIED...): never the unit
};

// How one failure is accounted.
struct FailureCharge {
  bool charge_unit = false;  // count an attempt against the unit's tiles
  bool blocked_now = false;  // the worker was just kept off the job
  std::chrono::milliseconds back_off{0};  // > 0: the worker gets nothing this long
};

class WorkerFailures {
 public:
  struct Options {
    int block_after = 3;
    std::chrono::milliseconds back_off_first{1000};
    std::chrono::milliseconds back_off_max{60000};
  };
  explicit WorkerFailures(Options options);

  FailureCharge failed(const std::string& worker_id, const std::string& job_id, FailureKind kind);
  // A unit kept from the worker: it works, whatever it failed before.
  void succeeded(const std::string& worker_id);

  bool blocked(const std::string& worker_id, const std::string& job_id) const;
  // The jobs the worker is kept off, sorted (farm workers).
  std::vector<std::string> blocked_jobs(const std::string& worker_id) const;

  // A job that failed or was cancelled, a worker that left: nothing more to remember of it. (A job
  // that succeeded stays listed in blocked_jobs, what farm workers shows, while its worker is.)
  void forget_job(const std::string& job_id);
  void forget_worker(const std::string& worker_id);

 private:
  struct Record {
    std::map<std::string, int> failures_by_job;  // this job's units it failed
    std::set<std::string> blocked;               // jobs it is kept off
    std::set<std::string> streak_jobs;           // the jobs it failed since its last success
    int back_offs = 0;                           // back-offs since its last success
  };

  const Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, Record> workers_;
};

}  // namespace farm
