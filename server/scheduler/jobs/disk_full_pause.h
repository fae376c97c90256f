#pragma once
// Dispatch paused while the scheduler cannot keep what it is given: a tile's result, a merged
// frame or a change to the job store refused for want of space (DiskFull). The first refusal
// pauses; slots claim nothing while paused (a tile rendered now could not be kept). A prober
// thread then looks at the free space of the folder that was full, after a backoff (`first`,
// doubling up to `max`): with room for the refused write, dispatch resumes by itself and
// `on_resume` runs (the dispatcher wakes its slots, the finisher retries the merges the disk
// refused); without, `on_still_full` may make room (the finisher takes back the tiles of the
// youngest of the jobs holding some, so that older ones can finish: the farm's own tiles would
// otherwise hold the disk for good), and it looks again at once if it did, later if not. A write refused again after a resume pauses again
// with the next, longer backoff; a write that goes through makes the next pause short again.
// At most one line a minute is logged about it (which folder, how much is free, how many writes
// were refused), and one when dispatch resumes after a pause that was logged.
//
// Lock: mutex_ is a leaf; on_resume runs without it, on the prober thread.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "server/common/disk_full.h"
#include "server/common/retry_backoff.h"

namespace farm {

class DiskFullPause {
 public:
  DiskFullPause(spdlog::logger& log, std::chrono::milliseconds first, std::chrono::milliseconds max);
  ~DiskFullPause();  // stop()
  DiskFullPause(const DiskFullPause&) = delete;
  DiskFullPause& operator=(const DiskFullPause&) = delete;

  // Called when dispatch resumes; set once, before anything is reported.
  void on_resume(std::function<void()> f) { on_resume_ = std::move(f); }
  // Called (on the prober thread, without the lock) when a look finds no room; true when it freed
  // some. Set once, before anything is reported.
  void on_still_full(std::function<bool()> f) { on_still_full_ = std::move(f); }
  // A write was refused: dispatch pauses (until the prober finds room again).
  void report(const DiskFull& refused);
  // A write went through: the next pause starts with the shortest backoff.
  void written();
  bool paused() const;
  // Ends the prober; nothing resumes after it. Idempotent.
  void stop();

 private:
  using Clock = std::chrono::steady_clock;
  void probe_loop();
  bool guarded(const std::function<bool()>& f);  // f(), false when it throws (logged)
  // Logs `line` (with how many writes were refused since the last line) unless a line about the
  // disk was logged less than a minute ago.
  void log_locked(const std::string& line);

  spdlog::logger& log_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;  // paused, stopping
  bool stopping_ = false;
  bool paused_ = false;
  bool announced_ = false;  // this pause was logged, so its end is too
  std::filesystem::path folder_;  // of the last refusal
  std::uint64_t needed_ = 0;      // bytes the last refusal wanted (0: unknown)
  int refused_ = 0;               // writes refused since the last line logged
  Clock::time_point paused_since_, next_probe_;
  RetryBackoff backoff_;
  std::function<void()> on_resume_;
  std::function<bool()> on_still_full_;
  std::thread prober_;  // last: started once the rest is built
};

}  // namespace farm
