#include "server/scheduler/dispatch/unit_metrics.h"

#include <algorithm>

namespace farm {

void UnitMetrics::kept(std::uint32_t units, Clock::time_point handed_out, Clock::time_point now) {
  const double seconds = std::max(0.0, std::chrono::duration<double>(now - handed_out).count());
  std::lock_guard lock(mutex_);
  done_ += units;
  std::size_t b = 0;
  while (b < kBuckets && seconds > kLatencyBounds[b]) ++b;
  ++buckets_[b];
  latency_sum_ += seconds;
  ++latency_count_;
  recent_.emplace_back(now, units);
  forget_old_locked(now);
}

void UnitMetrics::failed(std::uint32_t units) {
  std::lock_guard lock(mutex_);
  failed_ += units;
}

void UnitMetrics::forget_old_locked(Clock::time_point now) const {
  while (!recent_.empty() && now - recent_.front().first > kWindow) recent_.pop_front();
}

UnitMetrics::Snapshot UnitMetrics::snapshot(Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  forget_old_locked(now);
  Snapshot s;
  s.units_done = done_;
  s.units_failed = failed_;
  std::uint64_t in_window = 0;
  for (const auto& [when, units] : recent_) in_window += units;
  const double span = std::min(std::chrono::duration<double>(kWindow).count(),
                               std::chrono::duration<double>(now - started_).count());
  s.units_per_second = span > 0 ? static_cast<double>(in_window) / span : 0;
  std::uint64_t cumulative = 0;
  for (std::uint64_t count : buckets_) {
    cumulative += count;
    s.latency_buckets.push_back(cumulative);
  }
  s.latency_sum = latency_sum_;
  s.latency_count = latency_count_;
  return s;
}

}  // namespace farm
