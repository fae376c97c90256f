#pragma once
// What the dispatcher measures of units for `/metrics` (the dashboard's Prometheus endpoint):
// units kept and failed since the scheduler started, their rate over the last minute, and how
// long a batch took from being handed out to being kept (a histogram).
//
// Lock: UnitMetrics::mutex_ guards everything and is a leaf.
#include <chrono>
#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>
#include <vector>

namespace farm {

class UnitMetrics {
 public:
  using Clock = std::chrono::steady_clock;

  // The upper bounds (seconds) of the latency histogram's buckets; +Inf is implied.
  static constexpr double kLatencyBounds[] = {0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 300};
  static constexpr std::size_t kBuckets = sizeof kLatencyBounds / sizeof kLatencyBounds[0];

  // A batch of `units` kept, handed out at `handed_out`.
  void kept(std::uint32_t units, Clock::time_point handed_out, Clock::time_point now = Clock::now());
  void failed(std::uint32_t units);

  struct Snapshot {
    std::uint64_t units_done = 0;
    std::uint64_t units_failed = 0;
    double units_per_second = 0;  // kept over the last minute (or since the start, if shorter)
    std::vector<std::uint64_t> latency_buckets;  // cumulative counts, one per bound, then +Inf
    double latency_sum = 0;                       // seconds
    std::uint64_t latency_count = 0;              // batches
  };
  Snapshot snapshot(Clock::time_point now = Clock::now()) const;

 private:
  static constexpr auto kWindow = std::chrono::seconds(60);
  void forget_old_locked(Clock::time_point now) const;

  mutable std::mutex mutex_;
  const Clock::time_point started_ = Clock::now();
  std::uint64_t done_ = 0, failed_ = 0;
  std::uint64_t buckets_[kBuckets + 1] = {};
  double latency_sum_ = 0;
  std::uint64_t latency_count_ = 0;
  mutable std::deque<std::pair<Clock::time_point, std::uint32_t>> recent_;  // kept within kWindow
};

}  // namespace farm
