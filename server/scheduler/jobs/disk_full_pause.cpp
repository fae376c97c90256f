#include "server/scheduler/jobs/disk_full_pause.h"

#include <fmt/format.h>

#include <algorithm>

namespace farm {

namespace {

// Free space a probe wants when the refused write did not say how much it needed (the job
// store): a little more than a batch of SQLite pages.
constexpr std::uint64_t kMinRoom = 64 * 1024;

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

bool DiskFullPause::guarded(const std::function<bool()>& f) {
  // Nothing may end the prober (std::terminate): a store still full answers DiskFull here.
  try {
    return f();
  } catch (const DiskFull& e) {
    log_.debug("{}", e.what());
  } catch (const std::exception& e) {
    log_.error("while the disk was full: {}", e.what());
  }
  return false;
}

DiskFullPause::DiskFullPause(spdlog::logger& log, std::chrono::milliseconds first, std::chrono::milliseconds max)
    : log_(log), backoff_(first, max), prober_([this] { probe_loop(); }) {}

DiskFullPause::~DiskFullPause() { stop(); }

void DiskFullPause::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (prober_.joinable() && prober_.get_id() != std::this_thread::get_id()) prober_.join();
}

bool DiskFullPause::paused() const {
  std::lock_guard lock(mutex_);
  return paused_;
}

void DiskFullPause::written() {
  std::lock_guard lock(mutex_);
  if (!paused_) backoff_.reset();
}

void DiskFullPause::report(const DiskFull& refused) {
  std::lock_guard lock(mutex_);
  ++refused_;
  folder_ = refused.folder();
  needed_ = refused.needed();
  if (!paused_) {
    paused_ = true;
    paused_since_ = Clock::now();
    next_probe_ = paused_since_ + backoff_.next();
    wake_.notify_all();
  }
  log_locked(fmt::format("{}; dispatch paused, free space looked at again in {:.0f} s", refused.what(),
                         seconds(next_probe_ - Clock::now())));
}

void DiskFullPause::log_locked(const std::string& line) {
  int skipped = 0;
  if (!backoff_.log_now(skipped)) return;
  announced_ = true;
  log_.warn("{} ({} write{} refused since the last report)", line, refused_, refused_ == 1 ? "" : "s");
  refused_ = 0;
}

void DiskFullPause::probe_loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (!paused_) {
      wake_.wait(lock);
      continue;
    }
    if (Clock::now() < next_probe_) {
      wake_.wait_until(lock, next_probe_);
      continue;
    }
    const std::filesystem::path folder = folder_;
    const std::uint64_t wanted = std::max(needed_, kMinRoom);
    lock.unlock();
    const std::optional<std::uint64_t> free = free_bytes(folder);
    lock.lock();
    if (stopping_ || !paused_) continue;
    if (!free || *free < wanted) {
      if (on_still_full_) {
        lock.unlock();
        const bool freed = guarded(on_still_full_);
        lock.lock();
        if (freed) continue;  // looked at again at once
      }
      next_probe_ = Clock::now() + backoff_.next();
      log_locked(fmt::format("disk full in {}: {} free, {} wanted; dispatch still paused, looked at again in {:.0f} s",
                             folder.string(), free ? describe_bytes(*free) : "unknown", describe_bytes(wanted),
                             seconds(next_probe_ - Clock::now())));
      continue;
    }
    paused_ = false;
    if (announced_) {
      log_.info("space again in {}: {} free; dispatch resumed after {:.0f} s paused", folder.string(),
                describe_bytes(*free), seconds(Clock::now() - paused_since_));
      announced_ = false;
    }
    lock.unlock();
    if (on_resume_) guarded([this] { on_resume_(); return true; });
    lock.lock();
  }
}

}  // namespace farm
