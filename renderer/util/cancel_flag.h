#pragma once
// How a caller stops a render in progress: a cancellation token that the engines poll between
// small pieces of work (a few samples of a pixel, a batch of triangles of a bin), so that a
// render stops within milliseconds of a cancel or a deadline whatever its spp or resolution.
//
// One flag is shared by every thread working for one caller. cancel() may come from any thread;
// the deadline is checked by the pollers themselves, so a render with a deadline needs no thread
// watching it. Once stopped, a flag stays stopped with the first reason it recorded.
//
// Polling is an atomic load, plus a clock read when there is a deadline (over 100 ns where the
// clock is not in the vDSO), which is why hot loops poll through CancelPoll: once every few units
// of work rather than at every unit. Relaxed atomics suffice: the flag publishes no data, it only
// says stop, and a poller that sees it a moment late merely does one more unit of work.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>

namespace farm {

enum class StopReason : std::uint8_t {
  None,       // not stopped: a render that returns this ran to the end
  Cancelled,  // cancel() was called
  Deadline,   // the deadline passed
};

class CancelFlag {
 public:
  using Clock = std::chrono::steady_clock;

  CancelFlag() = default;  // no deadline: stops only when cancelled
  explicit CancelFlag(Clock::time_point deadline) : deadline_(deadline) {}
  CancelFlag(const CancelFlag&) = delete;
  CancelFlag& operator=(const CancelFlag&) = delete;

  // A wall-clock deadline (gRPC's), as a steady one from now on; system_clock's max() = none.
  static Clock::time_point steady_deadline(std::chrono::system_clock::time_point deadline);

  // A flag nobody cancels and without a deadline: what a render that must finish is given.
  static const CancelFlag& never();

  // Asks every poller to stop. Any thread, any number of times.
  void cancel() noexcept { trip(StopReason::Cancelled); }

  // True once cancelled, or once the deadline has passed; stays true.
  bool stop_requested() const noexcept {
    if (reason_.load(std::memory_order_relaxed) != StopReason::None) return true;
    if (deadline_ != Clock::time_point::max() && Clock::now() >= deadline_) {
      return trip(StopReason::Deadline);
    }
    if (counting_polls_) [[unlikely]] {
      if (polls_left_.fetch_sub(1, std::memory_order_relaxed) <= 1) return trip(StopReason::Cancelled);
    }
    return false;
  }

  // Why it stopped; None while it has not.
  StopReason reason() const noexcept { return reason_.load(std::memory_order_relaxed); }
  Clock::time_point deadline() const { return deadline_; }

  // For tests: the flag cancels itself at its `polls`-th poll (>= 1), a cancel that arrives in the
  // middle of a render at a point that does not depend on timing. Call before polling starts.
  void cancel_at_poll(std::int64_t polls) {
    polls_left_.store(polls, std::memory_order_relaxed);
    counting_polls_ = true;
  }

 private:
  bool trip(StopReason why) const noexcept {
    StopReason none = StopReason::None;
    reason_.compare_exchange_strong(none, why, std::memory_order_relaxed);
    return true;
  }

  Clock::time_point deadline_ = Clock::time_point::max();
  mutable std::atomic<StopReason> reason_{StopReason::None};
  bool counting_polls_ = false;
  mutable std::atomic<std::int64_t> polls_left_{0};
};

// Thrown by set-up work that a CancelFlag stopped (a frame's raster set-up, a BVH build): unlike
// a tile, which returns its StopReason, such work has nothing partial to give back, and it runs
// under callers (caches, thread pools) that pass exceptions through.
class RenderStopped : public std::exception {
 public:
  explicit RenderStopped(StopReason reason) : reason_(reason) {}
  StopReason reason() const noexcept { return reason_; }
  const char* what() const noexcept override {
    return reason_ == StopReason::Deadline ? "the deadline passed during set-up" : "cancelled during set-up";
  }

 private:
  StopReason reason_;
};

// Polls a CancelFlag once every `every` units of work, the unit being whatever the loop counts (a
// ray traced, a triangle drawn): between looks a hot loop pays one decrement. The first unit
// looks at once, so a render given a stopped flag does no work. Once it has said stop it keeps
// saying so without looking again, so nested loops that share one can each see it and unwind.
// One per thread.
class CancelPoll {
 public:
  CancelPoll(const CancelFlag& flag, int every) : flag_(flag), every_(every) {}

  // Counts `units` of work about to be done; true when the flag asks to stop (looked at when
  // `every` units have been counted since the last look; `units` >= `every` looks now).
  bool operator()(int units = 1) {
    if (stopped_) return true;
    left_ -= units;
    if (left_ > 0) return false;
    left_ = every_;
    stopped_ = flag_.stop_requested();
    return stopped_;
  }

  // The same, throwing RenderStopped instead of returning true: for set-up work.
  void throw_if_stopped(int units = 1) {
    if ((*this)(units)) throw RenderStopped(flag_.reason());
  }

  // Whether a look has said stop.
  bool stopped() const { return stopped_; }
  const CancelFlag& flag() const { return flag_; }

 private:
  const CancelFlag& flag_;
  const int every_;
  int left_ = 1;
  bool stopped_ = false;
};

}  // namespace farm
