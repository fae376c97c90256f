#pragma once
// The job store's server away (a PostgreSQL store that stopped, restarted or lost its link:
// StoreUnavailable). Nothing the scheduler does without its store can be kept, and none of it is
// the job's fault nor a worker's: no attempt is counted, no job fails. A result rendered while the
// store is away is kept on disk and marked done once it answers again (the slot that holds it
// waits, asking every second); slots claim nothing meanwhile (their claims fail and they wait);
// the workers stay registered (the registry lives in memory). When a store call answers again
// after an outage, `on_back` runs once: the scheduler looks at every active job for frames whose
// merge or end the outage interrupted. A line is logged when the store goes away (then at most
// once a minute while it stays away) and one when it is back.
//
// Lock: mutex_ is a leaf; on_back runs without it.
#include <chrono>
#include <functional>
#include <mutex>
#include <optional>

#include <spdlog/logger.h>

#include "server/common/retry_backoff.h"
#include "server/scheduler/store/postgres_connection.h"

namespace farm {

class StoreOutage {
 public:
  explicit StoreOutage(spdlog::logger& log) : log_(log), log_backoff_(kRetry, kRetry) {}

  // Called once, on the thread of the call that found the store back; set before anything reports.
  void on_back(std::function<void()> f) { on_back_ = std::move(f); }
  // A store call failed for want of its server.
  void report(const StoreUnavailable& e);
  // A store call answered: ends an outage (logged, and on_back run) if there was one. Never
  // throws: what on_back meets is reported (an outage again) or logged.
  void answered();

  // `call()` until the store answers: while it is away, again every second, until `stopping()`
  // says to give up (nullopt then). Other exceptions pass through.
  template <typename F, typename Stop>
  auto when_answered(F&& call, Stop&& stopping) -> std::optional<decltype(call())> {
    for (;;) {
      try {
        auto result = call();
        answered();
        return result;
      } catch (const StoreUnavailable& e) {
        report(e);
      }
      if (stopping(kRetry)) return std::nullopt;
    }
  }

  // How long a caller waits before asking the store again.
  static constexpr std::chrono::milliseconds kRetry{1000};

 private:
  using Clock = std::chrono::steady_clock;
  spdlog::logger& log_;
  std::mutex mutex_;
  std::optional<Clock::time_point> away_since_;
  int failed_calls_ = 0;  // since the last line logged
  RetryBackoff log_backoff_;
  std::function<void()> on_back_;
};

}  // namespace farm
