#include "server/scheduler/job_watch.h"

#include "server/scheduler/scheduler_core.h"

namespace farm {

namespace {

// A watch of a job on a shared store hears nothing for this long: the job is read again.
constexpr auto kQuietWatchPoll = std::chrono::seconds(3);

}  // namespace

JobWatch::JobWatch(SchedulerCore& core, std::string job_id, std::shared_ptr<JobEventQueue> queue,
                   std::optional<std::string> only_owner)
    : core_(core), job_id_(std::move(job_id)), only_owner_(std::move(only_owner)), queue_(std::move(queue)) {}

JobWatch::~JobWatch() { core_.unwatch(job_id_, queue_); }

bool JobWatch::dropped() { return queue_->dropped(); }

bool JobWatch::next(v1::JobEvent& event, std::chrono::milliseconds wait) {
  const Clock::time_point until = Clock::now() + wait;
  while (true) {
    const auto left = std::max(std::chrono::milliseconds(0),
                               std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()));
    if (queue_->pop(event, left)) {
      if (only_owner_ && event.job().owner() != *only_owner_) continue;
    } else if (!read_again(event)) {
      return false;
    }
    heard_ = Clock::now();
    if (event.has_state_changed()) last_ = event.job().state();
    return true;
  }
}

bool JobWatch::read_again(v1::JobEvent& event) {
  if (job_id_ == JobEvents::kEveryJob || !core_.store().is_shared()) return false;
  if (Clock::now() - heard_ < kQuietWatchPoll) return false;
  heard_ = Clock::now();
  std::optional<v1::Job> now;
  try {
    now = core_.get_job(job_id_);
  } catch (const StoreUnavailable&) {
    return false;  // the store away: the watch waits for it, as the job does
  }
  if (!now || now->state() == last_) return false;
  event.Clear();
  *event.mutable_job() = std::move(*now);
  event.mutable_state_changed()->set_from(last_);
  event.mutable_state_changed()->set_to(event.job().state());
  return true;
}

}  // namespace farm
