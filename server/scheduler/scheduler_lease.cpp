#include "server/scheduler/scheduler_lease.h"

#include "server/common/job_state.h"

namespace farm {

SchedulerLease::SchedulerLease(JobStore& store, StoreOutage& outage, spdlog::logger& log,
                               std::chrono::milliseconds length, std::function<void()> on_reaped)
    : store_(store), outage_(outage), log_(log), length_(length), on_reaped_(std::move(on_reaped)) {
  // Held before the first claim can mark a unit with this scheduler.
  store_.leases().hold_lease(unix_ms_now() + length_.count());
  thread_ = std::thread([this] { renew_loop(); });
}

SchedulerLease::~SchedulerLease() { stop(); }

void SchedulerLease::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  try {
    store_.leases().drop_lease();
  } catch (const std::exception& e) {
    log_.warn("giving up the scheduler's lease: {} (it runs out by itself)", e.what());
  }
}

void SchedulerLease::renew_loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, length_ / 3, [this] { return stopping_; });
    if (stopping_) return;
    lock.unlock();
    renew_and_reap();
    lock.lock();
  }
}

void SchedulerLease::renew_and_reap() {
  // Nothing may end this thread (std::terminate): a failure is logged and the next round tries.
  try {
    const std::int64_t now = unix_ms_now();
    store_.leases().hold_lease(now + length_.count());
    const std::vector<ReapedScheduler> reaped = store_.leases().reap_expired(now);
    outage_.answered();
    for (const ReapedScheduler& r : reaped) {
      log_.warn("scheduler {}: its lease ran out; its {} running unit{} queued again", r.id, r.tiles_queued_again,
                r.tiles_queued_again == 1 ? "" : "s");
    }
    if (!reaped.empty() && on_reaped_) on_reaped_();
  } catch (const StoreUnavailable& e) {
    outage_.report(e);
  } catch (const std::exception& e) {
    log_.error("renewing the scheduler's lease: {}", e.what());
  }
}

}  // namespace farm
