#include "server/scheduler/worker_registry.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace farm {

using Clock = WorkerEntry::Clock;

WorkerRegistry::WorkerRegistry(const SchedulerOptions& options, spdlog::logger& log, Silent on_silent)
    : options_(options), log_(log), on_silent_(std::move(on_silent)), monitor_([this] { monitor_loop(); }) {}

WorkerRegistry::~WorkerRegistry() { stop(); }

void WorkerRegistry::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (monitor_.joinable()) monitor_.join();
}

std::shared_ptr<WorkerEntry> WorkerRegistry::add(std::shared_ptr<TileWorker> worker, bool registered) {
  auto entry = std::make_shared<WorkerEntry>();
  entry->worker = std::move(worker);
  entry->registered = registered;
  {
    std::lock_guard lock(mutex_);
    entry->id = fmt::format("w{}-{}", ++next_id_, entry->worker->describe());
    workers_.emplace(entry->id, entry);
  }
  log_.info("worker {} added{}", entry->id, registered ? " (registered)" : "");
  return entry;
}

bool WorkerRegistry::remove(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end()) return false;
    it->second->removed = true;
    workers_.erase(it);
  }
  log_.warn("worker {} removed: {}", worker_id, reason);
  changed_.notify_all();
  return true;
}

bool WorkerRegistry::heartbeat(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  auto it = workers_.find(worker_id);
  if (it == workers_.end()) return false;
  it->second->last_heartbeat = Clock::now();
  return true;
}

std::size_t WorkerRegistry::count() const {
  std::lock_guard lock(mutex_);
  return workers_.size();
}

bool WorkerRegistry::await_up(WorkerEntry& w) {
  std::unique_lock lock(mutex_);
  const auto gone = [&] { return stopping_ || w.removed; };
  while (!gone() && w.down) {
    if (Clock::now() < w.probe_after) {
      changed_.wait_until(lock, w.probe_after, gone);
      continue;
    }
    lock.unlock();
    const bool up = w.worker->probe(options_.probe_interval);
    lock.lock();
    if (!up) {
      changed_.wait_for(lock, options_.probe_interval / 4, gone);
      continue;
    }
    // Each of the worker's slots probes it; the first to hear an answer says so.
    if (w.down) log_.info("worker {} is up", w.id);
    w.down = false;
  }
  return !gone();
}

bool WorkerRegistry::available(const WorkerEntry& w) const {
  std::lock_guard lock(mutex_);
  return !stopping_ && !w.removed && !w.down;
}

void WorkerRegistry::mark_down(WorkerEntry& w, std::chrono::milliseconds wait) {
  std::lock_guard lock(mutex_);
  w.down = true;
  w.probe_after = Clock::now() + wait;
}

int WorkerRegistry::slots_up() const {
  std::lock_guard lock(mutex_);
  int slots = 0;
  for (const auto& [id, w] : workers_) slots += w->down ? 0 : std::max(1, options_.tiles_per_worker);
  return slots;
}

void WorkerRegistry::monitor_loop() {
  const auto limit = options_.heartbeat_interval * options_.missed_heartbeats;
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    changed_.wait_for(lock, options_.heartbeat_interval / 2);
    std::vector<std::string> silent;
    for (const auto& [id, w] : workers_) {
      if (w->registered && Clock::now() - w->last_heartbeat > limit) silent.push_back(id);
    }
    // on_silent removes the worker (this registry's lock again) and cancels its calls.
    lock.unlock();
    for (const std::string& id : silent) on_silent_(id, fmt::format("no heartbeat for {} ms", limit.count()));
    lock.lock();
  }
}

}  // namespace farm
