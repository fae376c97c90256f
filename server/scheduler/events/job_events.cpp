#include "server/scheduler/events/job_events.h"

#include <cstdint>
#include <utility>

#include "server/common/job_state.h"

namespace farm {

bool JobEventQueue::pop(v1::JobEvent& event, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [&] { return !events_.empty(); })) return false;
  event = std::move(events_.front());
  events_.pop_front();
  return true;
}

void JobEventQueue::push(const v1::JobEvent& event) {
  {
    std::lock_guard lock(mutex_);
    if (events_.size() >= capacity_) {
      events_.pop_front();
      dropped_ = true;
    }
    events_.push_back(event);
  }
  ready_.notify_all();
}

bool JobEventQueue::dropped() {
  std::lock_guard lock(mutex_);
  return std::exchange(dropped_, false);
}

void JobEvents::subscribe(const std::string& job_id, std::shared_ptr<JobEventQueue> queue) {
  std::lock_guard lock(mutex_);
  watchers_.emplace(job_id, std::move(queue));
}

std::optional<v1::Job> JobEvents::subscribe_and_read(const std::string& job_id,
                                                     std::shared_ptr<JobEventQueue> queue) {
  std::lock_guard lock(mutex_);
  watchers_.emplace(job_id, std::move(queue));
  return store_.jobs().get_job(job_id);
}

void JobEvents::unsubscribe(const std::string& job_id, const std::shared_ptr<JobEventQueue>& queue) {
  std::lock_guard lock(mutex_);
  auto [begin, end] = watchers_.equal_range(job_id);
  for (auto it = begin; it != end; ++it) {
    if (it->second == queue) {
      watchers_.erase(it);
      return;
    }
  }
}

void JobEvents::publish(const std::string& job_id, const std::function<void(v1::JobEvent&)>& fill) {
  // The job is read under the watchers' lock, so that events from concurrent slots reach a
  // watcher in the order of the store's changes: tiles_done never goes back.
  std::lock_guard lock(mutex_);
  v1::JobEvent event;
  *event.mutable_job() = *store_.jobs().get_job(job_id);
  fill(event);
  push_locked(event);
}

void JobEvents::publish_state(const v1::Job& job, v1::JobState from, const std::string& by) {
  std::lock_guard lock(mutex_);
  push_state_locked(job, from, by);
}

void JobEvents::publish_started(const std::string& job_id) {
  std::lock_guard lock(mutex_);  // read under it, as publish() does: in the store's order
  const std::optional<v1::Job> job = store_.jobs().get_job(job_id);
  if (job && job->state() == v1::JOB_STATE_RUNNING) push_state_locked(*job, v1::JOB_STATE_QUEUED);
}

void JobEvents::push_state_locked(const v1::Job& job, v1::JobState from, const std::string& by) {
  v1::JobEvent event;
  *event.mutable_job() = job;
  event.mutable_state_changed()->set_from(from);
  event.mutable_state_changed()->set_to(job.state());
  event.mutable_state_changed()->set_by(by);
  push_locked(event);
}

void JobEvents::listen(std::function<void(const v1::JobEvent&)> listener) {
  std::lock_guard lock(mutex_);
  listeners_.push_back(std::move(listener));
}

void JobEvents::relay_to(std::function<void(const v1::JobEvent&)> forward) {
  std::lock_guard lock(mutex_);
  forward_ = std::move(forward);
}

void JobEvents::publish_relayed(v1::JobEvent event) {
  std::lock_guard lock(mutex_);
  const std::string& id = event.job().job_id();
  if (watchers_.count(id) == 0 && watchers_.count(kEveryJob) == 0) return;  // nobody here watches it
  const std::optional<v1::Job> job = store_.jobs().get_job(id);
  if (!job) return;
  if (event.has_state_changed()) {
    if (event.state_changed().from() == job->state()) return;
    event.mutable_state_changed()->set_to(job->state());
  }
  *event.mutable_job() = *job;
  push_to_watchers_locked(event);
}

void JobEvents::push_locked(const v1::JobEvent& event) {
  log_locked(event);
  push_to_watchers_locked(event);
  if (forward_) forward_(event);
  for (const auto& listener : listeners_) listener(event);
}

void JobEvents::log_locked(const v1::JobEvent& event) {
  if (event.has_tile_finished() || event.has_snapshot()) return;
  // The job as the event left it, in the fields a reader of the log looks at: the whole job in
  // every entry would repeat its stats and times thousands of times.
  v1::JobEvent entry = event;
  v1::Job& job = *entry.mutable_job();
  job.Clear();
  const v1::Job& then = event.job();
  job.set_job_id(then.job_id());
  job.set_name(then.name());
  job.set_state(then.state());
  job.set_priority(then.priority());
  job.set_paused(then.paused());
  job.set_tiles_total(then.tiles_total());
  job.set_tiles_done(then.tiles_done());
  job.set_tile_failures(then.tile_failures());
  job.set_frames_total(then.frames_total());
  job.set_frames_done(then.frames_done());
  job.set_failure_reason(then.failure_reason());
  try {
    store_.log().append_log(entry, unix_ms_now(), event.has_state_changed() || event.has_updated());
  } catch (const std::exception&) {
    // The store full or away: the event still reaches its watchers; the log misses it.
  }
}

void JobEvents::push_to_watchers_locked(const v1::JobEvent& event) {
  auto [begin, end] = watchers_.equal_range(event.job().job_id());
  for (auto it = begin; it != end; ++it) it->second->push(event);
  auto [all, all_end] = watchers_.equal_range(kEveryJob);
  for (auto it = all; it != all_end; ++it) it->second->push(event);
}

}  // namespace farm
