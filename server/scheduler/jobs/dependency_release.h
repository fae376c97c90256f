#pragma once
// Dependencies settled as jobs end (docs/architecture.md, 3.3.3): a thread of its own
// (PeriodicThread) asks the store which waiting jobs their dependencies now decide
// (JobDependencies::release_waiting) and hands each change to `on_settled` (the core announces it,
// and queues or stops the job's units). It looks at once, when woken (a job ended here: wake()),
// and every `every` besides, which catches jobs that ended on another scheduler of a shared store,
// or whose release a crash interrupted: the release is one transaction a round, so after a kill
// it is done whole by whichever scheduler looks next, and only once.
#include <chrono>
#include <functional>
#include <vector>

#include <spdlog/logger.h>

#include "server/common/periodic_thread.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

class DependencyRelease {
 public:
  DependencyRelease(JobStore& store, spdlog::logger& log, std::chrono::milliseconds every,
                    std::function<void(const std::vector<ReleasedJob>&)> on_settled);

  void wake() { thread_.wake(); }  // look now; never blocks for long
  void stop() { thread_.stop(); }  // idempotent; waits for a release under way

 private:
  void release();

  JobStore& store_;
  spdlog::logger& log_;
  const std::function<void(const std::vector<ReleasedJob>&)> on_settled_;
  PeriodicThread thread_;  // last: its first run uses the rest
};

}  // namespace farm
