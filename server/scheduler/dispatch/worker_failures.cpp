#include "server/scheduler/dispatch/worker_failures.h"

#include <algorithm>

namespace farm {

WorkerFailures::WorkerFailures(Options options) : options_(options) {}

FailureCharge WorkerFailures::failed(const std::string& worker_id, const std::string& job_id, FailureKind kind) {
  std::lock_guard lock(mutex_);
  Record& r = workers_[worker_id];
  FailureCharge charge;
  // Failing across jobs before this one: the worker, more likely than any of its units.
  const bool failing_elsewhere = std::any_of(r.streak_jobs.begin(), r.streak_jobs.end(),
                                             [&](const std::string& j) { return j != job_id; });
  if (kind != FailureKind::Refused) {
    const int in_job = ++r.failures_by_job[job_id];
    charge.charge_unit = in_job == 1 && !failing_elsewhere;
    const int block_after = kind == FailureKind::NeverRenders ? 1 : std::max(1, options_.block_after);
    if (in_job >= block_after && r.blocked.insert(job_id).second) charge.blocked_now = true;
  }
  r.streak_jobs.insert(job_id);
  if (kind == FailureKind::Refused || r.streak_jobs.size() >= 2) {
    auto wait = options_.back_off_first;
    for (int i = 0; i < r.back_offs && wait < options_.back_off_max; ++i) wait *= 2;
    charge.back_off = std::min(wait, std::max(options_.back_off_first, options_.back_off_max));
    ++r.back_offs;
  }
  return charge;
}

void WorkerFailures::succeeded(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  const auto it = workers_.find(worker_id);
  if (it == workers_.end()) return;
  Record& r = it->second;
  r.streak_jobs.clear();
  r.back_offs = 0;
}

bool WorkerFailures::blocked(const std::string& worker_id, const std::string& job_id) const {
  std::lock_guard lock(mutex_);
  const auto it = workers_.find(worker_id);
  return it != workers_.end() && it->second.blocked.contains(job_id);
}

std::vector<std::string> WorkerFailures::blocked_jobs(const std::string& worker_id) const {
  std::lock_guard lock(mutex_);
  const auto it = workers_.find(worker_id);
  if (it == workers_.end()) return {};
  return {it->second.blocked.begin(), it->second.blocked.end()};
}

void WorkerFailures::forget_job(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  for (auto& [id, r] : workers_) {
    r.failures_by_job.erase(job_id);
    r.blocked.erase(job_id);
  }
}

void WorkerFailures::forget_worker(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  workers_.erase(worker_id);
}

}  // namespace farm
