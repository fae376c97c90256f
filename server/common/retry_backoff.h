#pragma once
// Waits that double while something keeps failing (a full disk, a worker with a full disk), and a
// log line about it at most once a period, so that a lasting fault costs neither a tight loop
// nor a flood of log. A value type: its owner guards it.
#include <algorithm>
#include <chrono>
#include <optional>

namespace farm {

class RetryBackoff {
 public:
  using Clock = std::chrono::steady_clock;

  RetryBackoff(std::chrono::milliseconds first, std::chrono::milliseconds max,
               std::chrono::milliseconds log_every = std::chrono::minutes(1))
      : first_(first), max_(std::max(first, max)), next_(first), log_every_(log_every) {}

  // The wait before the next try; the one after is twice as long, up to the maximum.
  std::chrono::milliseconds next() {
    const std::chrono::milliseconds wait = next_;
    next_ = std::min(next_ * 2, max_);
    return wait;
  }
  // It worked: the next failure waits the shortest time again.
  void reset() { next_ = first_; }

  // True when a line may be logged now (none in the last period); `skipped` is then how many
  // times it said false since the last true.
  bool log_now(int& skipped) {
    const Clock::time_point now = Clock::now();
    if (logged_ && now - *logged_ < log_every_) {
      ++skipped_;
      return false;
    }
    logged_ = now;
    skipped = skipped_;
    skipped_ = 0;
    return true;
  }

 private:
  std::chrono::milliseconds first_, max_, next_;
  std::chrono::milliseconds log_every_;
  std::optional<Clock::time_point> logged_;
  int skipped_ = 0;
};

}  // namespace farm
