#include "server/scheduler/store/store_outage.h"

namespace farm {

void StoreOutage::report(const StoreUnavailable& e) {
  std::lock_guard lock(mutex_);
  if (!away_since_) away_since_ = Clock::now();
  ++failed_calls_;
  int skipped = 0;
  if (!log_backoff_.log_now(skipped)) return;
  log_.warn("{}; no unit is claimed or marked until it answers ({} store call{} failed so far)", e.what(),
            failed_calls_, failed_calls_ == 1 ? "" : "s");
}

void StoreOutage::answered() {
  {
    std::lock_guard lock(mutex_);
    if (!away_since_) return;
    log_.info("job store answers again after {:.1f} s away; {} store call{} had failed",
              std::chrono::duration<double>(Clock::now() - *away_since_).count(), failed_calls_,
              failed_calls_ == 1 ? "" : "s");
    away_since_.reset();
    failed_calls_ = 0;
    log_backoff_ = RetryBackoff(kRetry, kRetry);  // the next outage is logged at once
  }
  if (!on_back_) return;
  // Nothing it meets may reach the caller, which asked the store something else: a store away
  // again is an outage again, anything else is logged.
  try {
    on_back_();
  } catch (const StoreUnavailable& e) {
    report(e);
  } catch (const std::exception& e) {
    log_.error("looking at the active jobs after the store came back: {}", e.what());
  }
}

}  // namespace farm
