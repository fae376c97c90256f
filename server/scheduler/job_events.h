#pragma once
// WatchJob's plumbing: who watches which job, and the events they are sent (tiles finished or
// failed, state changes). A watcher subscribes with a JobEventQueue and pops from it at its own
// pace; publishing never waits for a watcher.
//
// Locks: JobEvents::mutex_ guards the subscriptions and is held while an event is made and pushed
// to every subscriber of its job; under it the job store's lock (to read the job), each queue's
// lock and the relay's queue (forward_) are taken, all leaves. No other lock of the scheduler is
// held when an event is published, so it takes part in no cycle.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "proto/farm.pb.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

// A WatchJob subscription: events of one job, in order.
class JobEventQueue {
 public:
  // False when `timeout` passed with nothing to pop.
  bool pop(v1::JobEvent& event, std::chrono::milliseconds timeout);
  void push(const v1::JobEvent& event);

 private:
  std::mutex mutex_;  // guards events_
  std::condition_variable ready_;
  std::deque<v1::JobEvent> events_;
};

class JobEvents {
 public:
  explicit JobEvents(const JobStore& store) : store_(store) {}

  // `queue` gets the events of `job_id` published from now on, until unsubscribe().
  void subscribe(const std::string& job_id, std::shared_ptr<JobEventQueue> queue);
  void unsubscribe(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue);

  // An event carrying the job as the store has it now, filled in by `fill`.
  void publish(const std::string& job_id, const std::function<void(v1::JobEvent&)>& fill);
  // `job` went from `from` to its state now.
  void publish_state(const v1::Job& job, v1::JobState from);

  // Every event published from now on is given to `forward` too (under mutex_, so in order; it
  // must not block): the schedulers sharing a store relay them to each other (event_relay.h).
  // An empty function stops it.
  void relay_to(std::function<void(const v1::JobEvent&)> forward);
  // An event another scheduler published: passed to this one's watchers of its job, if any,
  // carrying the job as the store has it now (a state change: to its state now; none when that is
  // where it came from). Not forwarded again.
  void publish_relayed(v1::JobEvent event);

 private:
  void push_locked(const v1::JobEvent& event);  // under mutex_: the watchers, then forward_
  void push_to_watchers_locked(const v1::JobEvent& event);

  const JobStore& store_;
  std::mutex mutex_;
  std::multimap<std::string, std::shared_ptr<JobEventQueue>> watchers_;
  std::function<void(const v1::JobEvent&)> forward_;
};

}  // namespace farm
