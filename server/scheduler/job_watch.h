#pragma once
// A caller's watch of one job's events, or of every job's, as the front door hands it out
// (SchedulerFrontDoor::watch_job, watch_every_job: front_door.h, where who may watch is decided).
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "proto/farm.pb.h"

namespace farm {

class SchedulerCore;
class JobEventQueue;

// A caller's subscription to job events, from the moment it was made until it is destroyed.
class JobWatch {
 public:
  ~JobWatch();  // unsubscribed
  JobWatch(const JobWatch&) = delete;
  JobWatch& operator=(const JobWatch&) = delete;

  // A watch of one job: the job as it was once the watch had begun (no event falls between the
  // two). Empty for a watch of every job.
  const v1::Job& snapshot() const { return snapshot_; }
  // The next event the caller may see, waiting at most `wait`; false when none came. A watch of
  // one job on a store other schedulers share hears their events through the relay, which may
  // miss some: after a quiet while the job is read again, and a change of state comes as a
  // state_changed event all the same.
  bool next(v1::JobEvent& event, std::chrono::milliseconds wait);
  // Whether events were dropped since the last call (a bounded watch whose reader fell behind).
  bool dropped();

 private:
  friend class SchedulerFrontDoor;
  using Clock = std::chrono::steady_clock;
  // `queue`: subscribed to `job_id` already (SchedulerCore::watch or watch_from_now).
  JobWatch(SchedulerCore& core, std::string job_id, std::shared_ptr<JobEventQueue> queue,
           std::optional<std::string> only_owner);
  // The job read again after a quiet while, as a state_changed event when its state changed.
  bool read_again(v1::JobEvent& event);

  SchedulerCore& core_;
  const std::string job_id_;                     // JobEvents::kEveryJob for every job
  const std::optional<std::string> only_owner_;  // a submitter watching every job hears its own
  std::shared_ptr<JobEventQueue> queue_;
  v1::Job snapshot_;
  v1::JobState last_ = v1::JOB_STATE_UNSPECIFIED;  // the state the watcher was last told
  Clock::time_point heard_ = Clock::now();
};

}  // namespace farm
