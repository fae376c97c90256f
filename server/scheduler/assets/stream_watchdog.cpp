#include "server/scheduler/assets/stream_watchdog.h"

#include <algorithm>
#include <utility>

namespace farm {

StreamWatchdog::StreamWatchdog(std::chrono::milliseconds idle_limit)
    : idle_limit_(std::max(idle_limit, std::chrono::milliseconds(1))), thread_([this] { loop(); }) {}

StreamWatchdog::~StreamWatchdog() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

StreamWatchdog::Watch StreamWatchdog::watch(grpc::ServerContext& context) {
  std::lock_guard lock(mutex_);
  const std::uint64_t id = next_id_++;
  streams_.emplace(id, Stream{&context, Clock::now()});
  return Watch(this, id);
}

StreamWatchdog::Watch::Watch(Watch&& other) noexcept
    : owner_(std::exchange(other.owner_, nullptr)), id_(other.id_) {}

StreamWatchdog::Watch::~Watch() {
  if (!owner_) return;
  std::lock_guard lock(owner_->mutex_);
  owner_->streams_.erase(id_);
}

void StreamWatchdog::Watch::touch() {
  std::lock_guard lock(owner_->mutex_);
  owner_->streams_.at(id_).last = Clock::now();
}

bool StreamWatchdog::Watch::timed_out() const {
  std::lock_guard lock(owner_->mutex_);
  return owner_->streams_.at(id_).cancelled;
}

void StreamWatchdog::loop() {
  // Looked at four times per limit: a silent stream ends within 1.25 limits.
  const auto period = std::max(idle_limit_ / 4, std::chrono::milliseconds(1));
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, period, [this] { return stopping_; });
    const Clock::time_point now = Clock::now();
    for (auto& [id, s] : streams_) {
      if (s.cancelled || now - s.last <= idle_limit_) continue;
      s.cancelled = true;
      s.context->TryCancel();
    }
  }
}

}  // namespace farm
