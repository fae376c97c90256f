#pragma once
// The workers a scheduler renders on, and whether each can take tiles now.
//
// A worker starts down: it is probed (TileWorker::probe) before its first tile, and again after a
// call that says it is unreachable or too slow (mark_down). One prober thread probes every worker
// that is down: one with no connection at all is only asked to connect and looked at again soon
// (TileWorker::connected, which does not block), so a thousand unreachable addresses cost it no
// waiting. The first time a worker is up, `on_first_up` starts its slots (the dispatcher's
// threads): a worker that never answers has none. A static worker (`--worker`) is never dropped,
// only probed while down; a registered one (RegisterWorker) heartbeats, and the monitor thread
// hands one that stays silent for missed_heartbeats intervals to `on_silent` (the core removes it
// and requeues its tiles).
//
// A quarantined worker (its reply broke the rules of tile_result_check.h, or a spot check found
// its pixels wrong) stays listed, with the reason, but gets no more tiles, and its slots end. Its
// address stays quarantined for the life of the process: registering again does not clear it.
//
// Lock: WorkerRegistry::mutex_ guards the map, every entry's state (WorkerEntry's fields below
// the line), the quarantined addresses and stopping_. Nothing else is locked under it: probes,
// on_first_up and on_silent run without it. The dispatcher takes it under its own lock and the
// job store's (claiming, batch sizing), never the other way round.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/logger.h>

#include "server/common/recent_hashes.h"
#include "server/scheduler/options/scheduler_options.h"
#include "server/scheduler/workers/tile_worker.h"

namespace farm {

// What a worker said of itself when it registered (RegisterWorkerRequest, bounded); a static
// worker (--worker) says nothing.
struct WorkerFacts {
  int threads = 0;
  std::vector<std::string> engines = {};
  std::vector<std::string> tags = {};  // sorted, each once: what jobs' requirements may ask for
  std::string hostname = {};
  std::string version = {};
};

struct WorkerEntry {
  using Clock = std::chrono::steady_clock;

  std::string id;
  std::shared_ptr<TileWorker> worker;
  bool registered = false;
  WorkerFacts facts;
  std::chrono::system_clock::time_point added_at = std::chrono::system_clock::now();
  // ---- Under WorkerRegistry::mutex_:
  bool removed = false;
  bool down = true;  // probed before the first tile
  bool quarantined = false;
  std::string quarantine_reason;
  bool slots_started = false;  // on_first_up was called for it
  // A worker that just failed is left alone this long before it is probed: its channel may
  // still look connected for a moment after the process died.
  Clock::time_point probe_after = Clock::now();
  // How long the prober leaves a worker with no connection before it looks again: short at
  // first (a worker just started connects within milliseconds), longer while it stays away.
  std::chrono::milliseconds retry{0};
  Clock::time_point last_heartbeat = Clock::now();
  std::uint64_t units_done = 0;    // units it rendered that were kept
  std::uint64_t units_failed = 0;  // units whose call to it failed or whose worker was lost
  // Set by back_off (worker_failures.h): no units until then, and why.
  std::chrono::system_clock::time_point backed_off_until{};
  std::string back_off_reason;
  // Scenes whose job this worker was sent in a call it answered: later calls for them leave the
  // job text out (a worker that no longer holds one answers NOT_FOUND and is sent it again).
  RecentHashes scenes_sent{256};
};

// A worker as the registry sees it now (SchedulerCore::workers()).
struct WorkerStatus {
  std::string id;
  std::string address;  // TileWorker::describe()
  bool registered = false;
  bool up = false;
  bool quarantined = false;
  std::string quarantine_reason;
  WorkerFacts facts = {};
  std::chrono::system_clock::time_point added_at = {};
  std::chrono::system_clock::time_point last_heartbeat = {};  // registered workers
  std::uint64_t units_done = 0;
  std::uint64_t units_failed = 0;
  std::chrono::system_clock::time_point backed_off_until = {};  // in the future: backed off
  std::string back_off_reason = {};
  std::chrono::system_clock::time_point lost_at = {};  // set in lost_workers(): when it was removed
  std::string lost_reason = {};
};

class WorkerRegistry {
 public:
  using Silent = std::function<void(const std::string& worker_id, const std::string& reason)>;
  using FirstUp = std::function<void(const std::shared_ptr<WorkerEntry>& worker)>;

  // Starts the monitor and the prober: they call nothing before a worker is added.
  WorkerRegistry(const SchedulerOptions& options, spdlog::logger& log, Silent on_silent, FirstUp on_first_up);
  ~WorkerRegistry();  // stop()
  WorkerRegistry(const WorkerRegistry&) = delete;
  WorkerRegistry& operator=(const WorkerRegistry&) = delete;

  std::shared_ptr<WorkerEntry> add(std::shared_ptr<TileWorker> worker, bool registered, WorkerFacts facts = {});
  // Counts units the worker rendered and that were kept, or that failed on it (farm workers).
  void count_units(const std::string& worker_id, std::uint64_t done, std::uint64_t failed);
  // False when the worker is unknown (removed already).
  bool remove(const std::string& worker_id, const std::string& reason);
  bool heartbeat(const std::string& worker_id);  // false: unknown worker (register again)
  std::size_t count() const;

  // Blocks while `w` is down (the prober probes it). False once it is removed or quarantined, or
  // the registry stops: its slots end.
  bool await_up(WorkerEntry& w);
  // Up, not removed, not quarantined, and the registry not stopping: `w` may be handed a batch.
  bool available(const WorkerEntry& w) const;
  // Whether a worker other than `ids` is available now (one to check another's pixels).
  bool any_available_except(const std::set<std::string>& ids) const;
  // `w` gets no more tiles until it answers a probe, tried no sooner than `wait` from now.
  void mark_down(WorkerEntry& w, std::chrono::milliseconds wait);
  // mark_down for `wait`, shown as backed off until then with `reason` (farm workers): the worker
  // failed units of several jobs in a row, or refused calls (worker_failures.h).
  void back_off(WorkerEntry& w, std::chrono::milliseconds wait, const std::string& reason);
  // The worker gets no more tiles, and neither does a worker registering later at its address.
  // False when it is unknown or quarantined already.
  bool quarantine(const std::string& worker_id, const std::string& reason);
  // Undoes quarantine() when what the worker was caught on proved a property of the job (another
  // worker rendered the same impossible values): probed again, slots started once it is up.
  // False when it is unknown or not quarantined.
  bool release_quarantine(const std::string& worker_id, const std::string& reason);
  // Calls the workers that are up take at once: tiles_per_worker each.
  int slots_up() const;
  std::vector<WorkerStatus> workers() const;
  // Workers removed in the last hour (at most 64, newest last), with when and why: a worker
  // killed mid-job shows as lost rather than vanishing. One that registers again at the same
  // address is no longer listed here.
  std::vector<WorkerStatus> lost_workers() const;

  // Ends the monitor, the prober and every await_up. Idempotent.
  void stop();

 private:
  void monitor_loop();
  void prober_loop();

  const SchedulerOptions& options_;
  spdlog::logger& log_;
  Silent on_silent_;
  FirstUp on_first_up_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;  // a worker up, removed or quarantined, or stopping
  std::condition_variable probe_;    // wakes the prober: a worker added or marked down, or stopping
  bool stopping_ = false;
  std::uint64_t next_id_ = 0;
  std::map<std::string, std::shared_ptr<WorkerEntry>> workers_;
  std::map<std::string, std::string> quarantined_addresses_;  // address -> why
  std::vector<WorkerStatus> lost_;  // lost_workers(), oldest first
  // Declared last: started once the fields above exist.
  std::thread monitor_;
  std::thread prober_;
};

}  // namespace farm
