#pragma once
// The ends of jobs that take long, on a thread of their own: checking a job's hits against
// Embree (validate.embree_rays) and encoding its video (output.video) take seconds to minutes,
// and the dispatcher's slot that delivered the job's last tile would wait for them, its worker
// idle, every other job held back. Here jobs end one at a time, in the order they came; a job
// queued already is not queued again.
//
// stop() ends the thread: the end in progress sees stop_requested() (the video encoder polls
// it) and gives up, the queued ones are dropped. Their jobs stay RUNNING in the store, every frame
// merged, and the next scheduler on the data dir ends them (SchedulerCore resumes active jobs).
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <thread>

namespace farm {

class JobEndings {
 public:
  using End = std::function<void(const std::string& job_id)>;
  explicit JobEndings(End end);
  ~JobEndings();  // stop()
  JobEndings(const JobEndings&) = delete;
  JobEndings& operator=(const JobEndings&) = delete;

  // Queues the job's end; false when it is queued already, or when stopping.
  bool add(const std::string& job_id);
  // True once stop() was called: an end in progress should give up.
  bool stop_requested() const;
  // Idempotent.
  void stop();

 private:
  void loop();

  End end_;
  mutable std::mutex mutex_;  // guards the three below; a leaf
  std::deque<std::string> queue_;
  std::set<std::string> pending_;  // queued
  bool stopping_ = false;
  std::condition_variable wake_;
  std::thread thread_;  // declared last: started once the fields above exist
};

}  // namespace farm
