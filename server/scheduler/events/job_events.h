#pragma once
// WatchJob's plumbing: who watches which job, and the events they are sent (tiles finished or
// failed, state changes). A watcher subscribes with a JobEventQueue and pops from it at its own
// pace; publishing never waits for a watcher. Every event published here, but TileFinished (one
// a batch), also goes to the job's log in the store (EventLog::append_log: `farm log`, and
// `farm watch` of a finished job), in the order watchers get them; one the store cannot take is
// lost from the log only.
//
// Locks: JobEvents::mutex_ guards the subscriptions and is held while an event is made and pushed
// to every subscriber of its job; under it the job store's lock (to read the job), each queue's
// lock and the relay's queue (forward_) are taken, all leaves. No other lock of the scheduler is
// held when an event is published, so it takes part in no cycle.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

// A WatchJob subscription: events of one job (or of every job), in order. A queue of bounded
// `capacity` (a browser's, which may read slowly) drops its oldest events when full and says so
// (dropped()), so that its reader can start again from the jobs as they are.
class JobEventQueue {
 public:
  explicit JobEventQueue(std::size_t capacity = SIZE_MAX) : capacity_(capacity) {}
  // False when `timeout` passed with nothing to pop.
  bool pop(v1::JobEvent& event, std::chrono::milliseconds timeout);
  void push(const v1::JobEvent& event);
  // Whether events were dropped since the last call.
  bool dropped();

 private:
  const std::size_t capacity_;
  std::mutex mutex_;  // guards events_ and dropped_
  std::condition_variable ready_;
  std::deque<v1::JobEvent> events_;
  bool dropped_ = false;
};

class JobEvents {
 public:
  explicit JobEvents(JobStore& store) : store_(store) {}

  // `queue` gets the events of `job_id` published from now on, until unsubscribe(); of every job
  // when `job_id` is kEveryJob (the dashboard's live tables).
  static constexpr const char* kEveryJob = "";
  void subscribe(const std::string& job_id, std::shared_ptr<JobEventQueue> queue);
  void unsubscribe(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue);
  // subscribe(), and the job read from the store, both under mutex_: every event `queue` gets is
  // made after the job was read, so none shows the job older than it, and none is missed. nullopt
  // when the store has no such job (the queue is subscribed all the same).
  std::optional<v1::Job> subscribe_and_read(const std::string& job_id, std::shared_ptr<JobEventQueue> queue);

  // An event carrying the job as the store has it now, filled in by `fill`.
  void publish(const std::string& job_id, const std::function<void(v1::JobEvent&)>& fill);
  // `job` went from `from` to its state now.
  void publish_state(const v1::Job& job, v1::JobState from, const std::string& by = {});
  // The job's first batch since it was queued was claimed: QUEUED -> RUNNING, unless it has
  // already left RUNNING (cancelled meanwhile), as the store has it now.
  void publish_started(const std::string& job_id);

  // Every event published from now on is given to `forward` too (under mutex_, so in order; it
  // must not block): the schedulers sharing a store relay them to each other (event_relay.h).
  // An empty function stops it.
  void relay_to(std::function<void(const v1::JobEvent&)> forward);
  // Every event published here from now on (not those relayed from other schedulers) is given to
  // `listener` too, in order, under mutex_: it must not block (the --notify-url webhook queues).
  void listen(std::function<void(const v1::JobEvent&)> listener);
  // An event another scheduler published: passed to this one's watchers of its job, if any,
  // carrying the job as the store has it now (a state change: to its state now; none when that is
  // where it came from). Not forwarded again.
  void publish_relayed(v1::JobEvent event);

 private:
  void push_locked(const v1::JobEvent& event);  // under mutex_: the log, the watchers, then forward_
  void push_state_locked(const v1::Job& job, v1::JobState from, const std::string& by = {});  // `job` went from `from` to its state
  void log_locked(const v1::JobEvent& event);
  void push_to_watchers_locked(const v1::JobEvent& event);

  JobStore& store_;
  std::mutex mutex_;
  std::multimap<std::string, std::shared_ptr<JobEventQueue>> watchers_;
  std::function<void(const v1::JobEvent&)> forward_;
  std::vector<std::function<void(const v1::JobEvent&)>> listeners_;
};

}  // namespace farm
