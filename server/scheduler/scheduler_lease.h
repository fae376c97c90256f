#pragma once
// A scheduler's lease on the units it hands out, when several schedulers share one store
// (PostgreSQL): renewed in the store every third of its length, and every other scheduler's that
// ran out reaped (its running units queued again, no attempt counted), so that the units of a
// scheduler killed mid-job come back within one lease and the others carry its jobs on. A store
// whose server is away renews nothing (StoreOutage is told); the lease runs on from where it was.
// stop() gives the lease up: the scheduler queued its own running units again as it stopped.
//
// Lock: mutex_ is a leaf; on_reaped runs without it, on the lease's thread.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "server/scheduler/store/job_store.h"
#include "server/scheduler/store/store_outage.h"

namespace farm {

class SchedulerLease {
 public:
  // Holds the lease of `store`'s scheduler (set_scheduler) for `length` from now on, and starts
  // renewing it; `on_reaped` runs after another scheduler was reaped (its units queued again, its
  // claims free).
  SchedulerLease(JobStore& store, StoreOutage& outage, spdlog::logger& log, std::chrono::milliseconds length,
                 std::function<void()> on_reaped);
  ~SchedulerLease();  // stop()
  SchedulerLease(const SchedulerLease&) = delete;
  SchedulerLease& operator=(const SchedulerLease&) = delete;

  // Ends the renewals and gives the lease up. Idempotent.
  void stop();

 private:
  void renew_loop();
  void renew_and_reap();

  JobStore& store_;
  StoreOutage& outage_;
  spdlog::logger& log_;
  std::chrono::milliseconds length_;
  std::function<void()> on_reaped_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace farm
