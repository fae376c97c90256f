#include "server/scheduler/jobs/job_endings.h"

#include <utility>

namespace farm {

JobEndings::JobEndings(End end) : end_(std::move(end)), thread_([this] { loop(); }) {}

JobEndings::~JobEndings() { stop(); }

bool JobEndings::add(const std::string& job_id) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || !pending_.insert(job_id).second) return false;
    queue_.push_back(job_id);
  }
  wake_.notify_one();
  return true;
}

bool JobEndings::stop_requested() const {
  std::lock_guard lock(mutex_);
  return stopping_;
}

void JobEndings::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void JobEndings::loop() {
  for (;;) {
    std::string job_id;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      job_id = std::move(queue_.front());
      queue_.pop_front();
      // Out of pending_ before it ends: an end that is refused (a full disk) and asked again
      // while it returns is queued again, not lost. A job asked again after it ended finds
      // itself final and returns.
      pending_.erase(job_id);
    }
    end_(job_id);  // catches what it throws (Finisher::end_in_background)
  }
}

}  // namespace farm
