#pragma once
// The scheduler's retention policy (`farm scheduler --keep-finished 7d`): a job that ended longer
// ago than that is deleted with its files (SchedulerCore::remove_finished_before), so the data dir
// does not grow without bound. Active jobs are never touched. A thread of its own (PeriodicThread)
// looks every tenth of the period (between 1 s and 10 min), so a job outlives its time by at most
// that much.
#include <chrono>
#include <cstdint>
#include <functional>

#include <spdlog/logger.h>

#include "server/common/periodic_thread.h"

namespace farm {

class RetentionSweeper {
 public:
  // `sweep(before_ms)` deletes the jobs that finished before Unix time `before_ms` and returns how
  // many; it is first called at once.
  RetentionSweeper(std::chrono::milliseconds keep, spdlog::logger& log,
                   std::function<std::size_t(std::int64_t before_ms)> sweep);

  void stop() { thread_.stop(); }  // idempotent; waits for a sweep under way

 private:
  void sweep_once();

  const std::chrono::milliseconds keep_;
  spdlog::logger& log_;
  const std::function<std::size_t(std::int64_t)> sweep_;
  PeriodicThread thread_;  // last: its first run uses the rest
};

}  // namespace farm
