#pragma once
// The worker's render threads: one fixed set shared by every RenderTile call. Each call splits its
// rectangle into small sub-tiles and queues them here, so one big tile uses every thread and
// concurrent tiles share them first come, first served. (ThreadPool serves one parallel_for at a
// time; this serves many callers at once.)
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace farm {

class TileExecutor {
 public:
  explicit TileExecutor(int threads);  // 0 = all hardware threads
  // Drops tasks not yet started and joins the threads.
  ~TileExecutor();
  TileExecutor(const TileExecutor&) = delete;
  TileExecutor& operator=(const TileExecutor&) = delete;

  int threads() const { return static_cast<int>(threads_.size()); }

  // Runs `task` on some thread. Tasks must not throw.
  void submit(std::function<void()> task);

 private:
  void loop();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> queue_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace farm
