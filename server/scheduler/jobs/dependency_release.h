#pragma once
// Dependencies settled as jobs end (docs/architecture.md, "Scheduling"): a thread of its own asks
// the store which waiting jobs their dependencies now decide (JobDependencies::release_waiting) and
// hands each change to `on_settled` (the core announces it, and queues or stops the job's units).
// It looks when woken (a job ended here: wake()) and every `every` besides, which catches jobs that
// ended on another scheduler of a shared store, or whose release a crash interrupted: the release
// is one transaction per round, so after a kill it is done whole by whichever scheduler looks next,
// and only once.
//
// Lock: DependencyRelease::mutex_ guards stopping_ and woken_ only; the release and the callback
// run without it, so wake() may be called from under any other lock (JobEvents' listeners).
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <spdlog/logger.h>

#include "server/scheduler/store/job_store.h"

namespace farm {

class DependencyRelease {
 public:
  DependencyRelease(JobStore& store, spdlog::logger& log, std::chrono::milliseconds every,
                    std::function<void(const std::vector<ReleasedJob>&)> on_settled);
  ~DependencyRelease();  // stop()
  DependencyRelease(const DependencyRelease&) = delete;
  DependencyRelease& operator=(const DependencyRelease&) = delete;

  void wake();  // look now; never blocks for long
  void stop();  // idempotent; waits for a release under way

 private:
  void loop();

  JobStore& store_;
  spdlog::logger& log_;
  const std::chrono::milliseconds every_;
  const std::function<void(const std::vector<ReleasedJob>&)> on_settled_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool woken_ = true;  // the first look is at once: jobs may be waiting since the last run
  std::thread thread_;
};

}  // namespace farm
