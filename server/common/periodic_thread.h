#pragma once
// A thread of its own that runs one task at once, then again every `every` and whenever woken,
// until stopped: the scheduler's retention sweep and its dependency release. The task runs with
// no lock held, so wake() may be called from under any other lock.
//
// Lock: mutex_ guards stopping_ and woken_ only.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace farm {

class PeriodicThread {
 public:
  PeriodicThread(std::chrono::milliseconds every, std::function<void()> task);
  ~PeriodicThread();  // stop()
  PeriodicThread(const PeriodicThread&) = delete;
  PeriodicThread& operator=(const PeriodicThread&) = delete;

  void wake();  // run the task again as soon as the current run, if any, ends
  void stop();  // idempotent; waits for a run under way

 private:
  void loop();

  const std::chrono::milliseconds every_;
  const std::function<void()> task_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool woken_ = false;
  std::thread thread_;  // last: started once the rest is built
};

}  // namespace farm
