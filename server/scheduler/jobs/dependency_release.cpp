#include "server/scheduler/jobs/dependency_release.h"

#include "server/common/job_state.h"

namespace farm {

DependencyRelease::DependencyRelease(JobStore& store, spdlog::logger& log, std::chrono::milliseconds every,
                                     std::function<void(const std::vector<ReleasedJob>&)> on_settled)
    : store_(store), log_(log), every_(every), on_settled_(std::move(on_settled)), thread_([this] { loop(); }) {}

DependencyRelease::~DependencyRelease() { stop(); }

void DependencyRelease::wake() {
  {
    std::lock_guard lock(mutex_);
    woken_ = true;
  }
  wake_.notify_all();
}

void DependencyRelease::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void DependencyRelease::loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    woken_ = false;
    lock.unlock();
    try {
      const std::vector<ReleasedJob> settled = store_.dependencies().release_waiting(unix_ms_now());
      if (!settled.empty()) on_settled_(settled);
    } catch (const std::exception& e) {
      // The store away or full: the next look tries again, and finds the same jobs.
      log_.warn("releasing jobs whose dependencies ended: {}", e.what());
    }
    lock.lock();
    wake_.wait_for(lock, every_, [&] { return stopping_ || woken_; });
  }
}

}  // namespace farm
