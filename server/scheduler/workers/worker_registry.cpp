#include "server/scheduler/workers/worker_registry.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace farm {

using Clock = WorkerEntry::Clock;

namespace {
// The prober's first look again at a worker with no connection; it doubles up to a quarter of
// the probe interval.
constexpr std::chrono::milliseconds kFirstRetry(5);
}  // namespace

WorkerRegistry::WorkerRegistry(const SchedulerOptions& options, spdlog::logger& log, Silent on_silent,
                               FirstUp on_first_up)
    : options_(options),
      log_(log),
      on_silent_(std::move(on_silent)),
      on_first_up_(std::move(on_first_up)),
      monitor_([this] { monitor_loop(); }),
      prober_([this] { prober_loop(); }) {}

WorkerRegistry::~WorkerRegistry() { stop(); }

void WorkerRegistry::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  probe_.notify_all();
  if (monitor_.joinable()) monitor_.join();
  if (prober_.joinable()) prober_.join();
}

std::shared_ptr<WorkerEntry> WorkerRegistry::add(std::shared_ptr<TileWorker> worker, bool registered,
                                                 WorkerFacts facts) {
  auto entry = std::make_shared<WorkerEntry>();
  entry->worker = std::move(worker);
  entry->registered = registered;
  entry->facts = std::move(facts);
  entry->retry = kFirstRetry;
  std::string quarantined;
  {
    std::lock_guard lock(mutex_);
    entry->id = fmt::format("w{}-{}", ++next_id_, entry->worker->describe());
    if (auto it = quarantined_addresses_.find(entry->worker->describe()); it != quarantined_addresses_.end()) {
      entry->quarantined = true;
      entry->quarantine_reason = it->second;
      quarantined = it->second;
    }
    workers_.emplace(entry->id, entry);
    // Back at its address: no longer listed as lost.
    std::erase_if(lost_, [&](const WorkerStatus& s) { return s.address == entry->worker->describe(); });
  }
  probe_.notify_all();
  log_.info("worker {} added{}", entry->id, registered ? " (registered)" : "");
  if (!quarantined.empty()) log_.warn("worker {} quarantined: its address was quarantined before: {}", entry->id, quarantined);
  return entry;
}

namespace {

// A worker as the registry sees it now; the heartbeat's steady time as wall-clock time.
WorkerStatus status_of(const std::string& id, const WorkerEntry& w) {
  const auto steady_now = std::chrono::steady_clock::now();
  const auto wall_now = std::chrono::system_clock::now();
  return {.id = id,
          .address = w.worker->describe(),
          .registered = w.registered,
          .up = !w.down,
          .quarantined = w.quarantined,
          .quarantine_reason = w.quarantine_reason,
          .facts = w.facts,
          .added_at = w.added_at,
          .last_heartbeat = wall_now - std::chrono::duration_cast<std::chrono::system_clock::duration>(
                                           steady_now - w.last_heartbeat),
          .units_done = w.units_done,
          .units_failed = w.units_failed,
          .backed_off_until = w.backed_off_until,
          .back_off_reason = w.back_off_reason};
}

constexpr std::size_t kLostKept = 64;
constexpr auto kLostFor = std::chrono::hours(1);

}  // namespace

bool WorkerRegistry::remove(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end()) return false;
    it->second->removed = true;
    WorkerStatus lost = status_of(worker_id, *it->second);
    lost.lost_at = std::chrono::system_clock::now();
    lost.lost_reason = reason;
    lost_.push_back(std::move(lost));
    if (lost_.size() > kLostKept) lost_.erase(lost_.begin());
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

void WorkerRegistry::count_units(const std::string& worker_id, std::uint64_t done, std::uint64_t failed) {
  std::lock_guard lock(mutex_);
  auto it = workers_.find(worker_id);
  if (it == workers_.end()) return;
  it->second->units_done += done;
  it->second->units_failed += failed;
}

std::size_t WorkerRegistry::count() const {
  std::lock_guard lock(mutex_);
  return workers_.size();
}

bool WorkerRegistry::await_up(WorkerEntry& w) {
  std::unique_lock lock(mutex_);
  const auto gone = [&] { return stopping_ || w.removed || w.quarantined; };
  changed_.wait(lock, [&] { return gone() || !w.down; });
  return !gone();
}

bool WorkerRegistry::available(const WorkerEntry& w) const {
  std::lock_guard lock(mutex_);
  return !stopping_ && !w.removed && !w.down && !w.quarantined;
}

bool WorkerRegistry::any_available_except(const std::set<std::string>& ids) const {
  std::lock_guard lock(mutex_);
  if (stopping_) return false;
  for (const auto& [id, w] : workers_) {
    if (!w->down && !w->quarantined && !ids.contains(id)) return true;
  }
  return false;
}

void WorkerRegistry::mark_down(WorkerEntry& w, std::chrono::milliseconds wait) {
  {
    std::lock_guard lock(mutex_);
    w.down = true;
    w.probe_after = Clock::now() + wait;
    w.retry = kFirstRetry;
  }
  probe_.notify_all();
}

void WorkerRegistry::back_off(WorkerEntry& w, std::chrono::milliseconds wait, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    w.backed_off_until = std::chrono::system_clock::now() + wait;
    w.back_off_reason = reason;
  }
  mark_down(w, wait);
}

bool WorkerRegistry::quarantine(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end() || it->second->quarantined) return false;
    it->second->quarantined = true;
    it->second->quarantine_reason = reason;
    quarantined_addresses_[it->second->worker->describe()] = reason;
  }
  log_.error("worker {} quarantined: {}", worker_id, reason);
  changed_.notify_all();
  return true;
}

bool WorkerRegistry::release_quarantine(const std::string& worker_id, const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    auto it = workers_.find(worker_id);
    if (it == workers_.end() || !it->second->quarantined) return false;
    WorkerEntry& w = *it->second;
    w.quarantined = false;
    w.quarantine_reason.clear();
    quarantined_addresses_.erase(w.worker->describe());
    // Probed again, and its slots (which ended with the quarantine) started anew once it is up.
    // A slot that had not yet seen the quarantine carries on beside them: a worker released
    // gets at most one extra set of slots.
    w.down = true;
    w.probe_after = Clock::now();
    w.retry = kFirstRetry;
    w.slots_started = false;
  }
  log_.warn("worker {} released from quarantine: {}", worker_id, reason);
  probe_.notify_all();
  changed_.notify_all();
  return true;
}

int WorkerRegistry::slots_up() const {
  std::lock_guard lock(mutex_);
  int slots = 0;
  for (const auto& [id, w] : workers_) slots += w->down || w->quarantined ? 0 : std::max(1, options_.tiles_per_worker);
  return slots;
}

std::vector<WorkerStatus> WorkerRegistry::workers() const {
  std::lock_guard lock(mutex_);
  std::vector<WorkerStatus> out;
  for (const auto& [id, w] : workers_) out.push_back(status_of(id, *w));
  return out;
}

std::vector<WorkerStatus> WorkerRegistry::lost_workers() const {
  std::lock_guard lock(mutex_);
  std::vector<WorkerStatus> out;
  const auto now = std::chrono::system_clock::now();
  for (const WorkerStatus& s : lost_) {
    if (now - s.lost_at < kLostFor) out.push_back(s);
  }
  return out;
}

void WorkerRegistry::prober_loop() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    const Clock::time_point now = Clock::now();
    Clock::time_point next = now + options_.probe_interval;
    std::vector<std::shared_ptr<WorkerEntry>> due;
    for (const auto& [id, w] : workers_) {
      if (!w->down || w->quarantined) continue;
      if (w->probe_after <= now) {
        due.push_back(w);
      } else {
        next = std::min(next, w->probe_after);
      }
    }
    if (due.empty()) {
      probe_.wait_until(lock, next);
      continue;
    }
    // Probes run without the lock; one that connected but does not answer waits probe_interval.
    lock.unlock();
    enum class Outcome { NoConnection, NoAnswer, Up };
    std::vector<Outcome> outcomes;
    for (const auto& w : due) {
      if (!w->worker->connected()) {
        outcomes.push_back(Outcome::NoConnection);
      } else {
        outcomes.push_back(w->worker->probe(options_.probe_interval) ? Outcome::Up : Outcome::NoAnswer);
      }
    }
    lock.lock();
    std::vector<std::shared_ptr<WorkerEntry>> first_up;
    const Clock::time_point after = Clock::now();
    for (std::size_t i = 0; i < due.size(); ++i) {
      WorkerEntry& w = *due[i];
      if (w.removed || !w.down) continue;
      switch (outcomes[i]) {
        case Outcome::NoConnection:
          w.probe_after = after + w.retry;
          w.retry = std::min(w.retry * 2, std::max(kFirstRetry, std::chrono::milliseconds(options_.probe_interval / 4)));
          break;
        case Outcome::NoAnswer:
          w.probe_after = after + options_.probe_interval / 4;
          break;
        case Outcome::Up:
          log_.info("worker {} is up", w.id);
          w.down = false;
          if (!w.slots_started && !w.quarantined) {
            w.slots_started = true;
            first_up.push_back(due[i]);
          }
          break;
      }
    }
    changed_.notify_all();
    if (first_up.empty()) continue;
    lock.unlock();
    for (const auto& w : first_up) on_first_up_(w);
    lock.lock();
  }
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
