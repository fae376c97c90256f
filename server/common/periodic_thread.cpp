#include "server/common/periodic_thread.h"

#include <utility>

namespace farm {

PeriodicThread::PeriodicThread(std::chrono::milliseconds every, std::function<void()> task)
    : every_(every), task_(std::move(task)), thread_([this] { loop(); }) {}

PeriodicThread::~PeriodicThread() { stop(); }

void PeriodicThread::wake() {
  {
    std::lock_guard lock(mutex_);
    woken_ = true;
  }
  wake_.notify_all();
}

void PeriodicThread::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void PeriodicThread::loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    woken_ = false;
    lock.unlock();
    task_();
    lock.lock();
    wake_.wait_for(lock, every_, [&] { return stopping_ || woken_; });
  }
}

}  // namespace farm
