#pragma once
// Per-frame data an engine derives from a prepared scene and a frame's settings (the
// rasterizer's transformed, set-up and binned triangles), built once and shared by every tile of
// that frame (or, unbounded, what every frame of a job shares: model_geometry.h). Concurrent requests for the same key wait for a single build (each able to stop
// waiting when its own CancelFlag asks). A few recent frames
// are kept: a job renders one frame size, but a worker may interleave several jobs' tiles.
#include <chrono>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "renderer/util/cancel_flag.h"
#include "renderer/util/thread_pool.h"

namespace farm {

class FrameCache {
 public:
  static constexpr std::size_t kUnbounded = static_cast<std::size_t>(-1);
  explicit FrameCache(std::size_t capacity = kDefaultCapacity) : capacity_(capacity) {}

  // The value for `key`, built here by build() when no one has (or is building) it. A caller
  // waiting for another's build polls `cancel` and throws RenderStopped when it asks; a build
  // that its own caller's flag stopped (build() threw RenderStopped) is not cached, and its
  // waiters, whose flags have not stopped, build it again themselves.
  template <typename T, typename Build>
  std::shared_ptr<const T> get_or_build(const std::string& key, const CancelFlag& cancel, Build&& build) {
    for (;;) {
      std::promise<std::shared_ptr<const void>> promise;
      std::shared_future<std::shared_ptr<const void>> future;
      const void* tag = nullptr;  // the entry: its build's loops carry it (thread_pool.h)
      {
        std::lock_guard lock(mutex_);
        for (auto it = entries_.begin(); it != entries_.end(); ++it) {
          if (it->first == key) {
            entries_.splice(entries_.begin(), entries_, it);  // most recently used first
            future = it->second;
            tag = &*it;
            break;
          }
        }
        if (!future.valid()) {
          entries_.emplace_front(key, promise.get_future().share());
          tag = &entries_.front();
          if (entries_.size() > capacity_) entries_.pop_back();
        }
      }
      if (future.valid()) {
        // A pool thread helps with the build's own loops meanwhile (thread_pool.h).
        while (future.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
          if (cancel.stop_requested()) throw RenderStopped(cancel.reason());
          if (!ThreadPool::help_while_waiting(tag, kHelpWait)) future.wait_for(kWaitPoll);
        }
        try {
          return std::static_pointer_cast<const T>(future.get());
        } catch (const RenderStopped&) {
          continue;  // the builder's caller gave up, not this one: build it here
        }
      }
      try {
        std::shared_ptr<const T> value;
        {
          const ThreadPool::LoopTag loops(tag);  // waiters may help with the build's loops
          value = build();
        }
        promise.set_value(value);
        return value;
      } catch (...) {
        forget(key);  // let a later request (or a waiter) try again
        promise.set_exception(std::current_exception());
        throw;
      }
    }
  }

 private:
  void forget(const std::string& key) {
    std::lock_guard lock(mutex_);
    entries_.remove_if([&](const auto& e) { return e.first == key; });
  }

  static constexpr std::size_t kDefaultCapacity = 4;
  const std::size_t capacity_;
  static constexpr std::chrono::milliseconds kWaitPoll{5};
  // A helping pool thread looks at the future this often when no loop is queued.
  static constexpr std::chrono::milliseconds kHelpWait{1};
  std::mutex mutex_;
  std::list<std::pair<std::string, std::shared_future<std::shared_ptr<const void>>>> entries_;
};

}  // namespace farm
