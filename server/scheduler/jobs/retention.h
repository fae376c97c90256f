#pragma once
// The scheduler's retention policy (`farm scheduler --keep-finished 7d`): a job that ended longer
// ago than that is deleted with its files (SchedulerCore::remove_finished_before), so the data dir
// does not grow without bound. Active jobs are never touched. A thread of its own looks every
// tenth of the period (between 1 s and 10 min), so a job outlives its time by at most that much.
//
// Lock: RetentionSweeper::mutex_ guards stopping_ only; the sweep runs without it.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

#include <spdlog/logger.h>

namespace farm {

class RetentionSweeper {
 public:
  // `sweep(before_ms)` deletes the jobs that finished before Unix time `before_ms` and returns how
  // many; it is first called at once.
  RetentionSweeper(std::chrono::milliseconds keep, spdlog::logger& log,
                   std::function<std::size_t(std::int64_t before_ms)> sweep);
  ~RetentionSweeper();  // stop()
  RetentionSweeper(const RetentionSweeper&) = delete;
  RetentionSweeper& operator=(const RetentionSweeper&) = delete;

  void stop();  // idempotent; waits for a sweep under way

 private:
  void loop();

  const std::chrono::milliseconds keep_;
  const std::chrono::milliseconds every_;
  spdlog::logger& log_;
  const std::function<std::size_t(std::int64_t)> sweep_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace farm
