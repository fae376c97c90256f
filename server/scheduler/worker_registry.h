#pragma once
// The workers a scheduler renders on, and whether each can take tiles now.
//
// A worker starts down: it is probed (TileWorker::probe) before its first tile, and again after a
// call that says it is unreachable or too slow (mark_down). A static worker (`--worker`) is never
// dropped, only probed while down; a registered one (RegisterWorker) heartbeats, and the monitor
// thread hands one that stays silent for missed_heartbeats intervals to `on_silent` (the core
// removes it and requeues its tiles).
//
// Lock: WorkerRegistry::mutex_ guards the map, every entry's state (WorkerEntry's fields below
// the line) and stopping_. Nothing else is locked under it: probes and on_silent run without it.
// The dispatcher takes it under its own lock and the job store's (claiming, batch sizing),
// never the other way round.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <spdlog/logger.h>

#include "server/scheduler/scheduler_options.h"
#include "server/scheduler/tile_worker.h"

namespace farm {

struct WorkerEntry {
  using Clock = std::chrono::steady_clock;

  std::string id;
  std::shared_ptr<TileWorker> worker;
  bool registered = false;
  // ---- Under WorkerRegistry::mutex_:
  bool removed = false;
  bool down = true;  // probed before the first tile
  // A worker that just failed is left alone this long before it is probed: its channel may
  // still look connected for a moment after the process died.
  Clock::time_point probe_after = Clock::now();
  Clock::time_point last_heartbeat = Clock::now();
};

class WorkerRegistry {
 public:
  using Silent = std::function<void(const std::string& worker_id, const std::string& reason)>;

  // Starts the monitor thread: it cannot call `on_silent` before a registered worker is added.
  WorkerRegistry(const SchedulerOptions& options, spdlog::logger& log, Silent on_silent);
  ~WorkerRegistry();  // stop()
  WorkerRegistry(const WorkerRegistry&) = delete;
  WorkerRegistry& operator=(const WorkerRegistry&) = delete;

  std::shared_ptr<WorkerEntry> add(std::shared_ptr<TileWorker> worker, bool registered);
  // False when the worker is unknown (removed already).
  bool remove(const std::string& worker_id, const std::string& reason);
  bool heartbeat(const std::string& worker_id);  // false: unknown worker (register again)
  std::size_t count() const;

  // Blocks while `w` is down, probing it every probe_interval until it answers. False once it is
  // removed or the registry stops: its slots end.
  bool await_up(WorkerEntry& w);
  // Up, not removed, and the registry not stopping: `w` may be handed a batch.
  bool available(const WorkerEntry& w) const;
  // `w` gets no more tiles until it answers a probe, tried no sooner than `wait` from now.
  void mark_down(WorkerEntry& w, std::chrono::milliseconds wait);
  // Calls the workers that are up take at once: tiles_per_worker each.
  int slots_up() const;

  // Ends the monitor and every await_up. Idempotent.
  void stop();

 private:
  void monitor_loop();

  const SchedulerOptions& options_;
  spdlog::logger& log_;
  Silent on_silent_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;  // a worker removed, or stopping
  bool stopping_ = false;
  std::uint64_t next_id_ = 0;
  std::map<std::string, std::shared_ptr<WorkerEntry>> workers_;
  std::thread monitor_;  // declared last: started once the fields above exist
};

}  // namespace farm
