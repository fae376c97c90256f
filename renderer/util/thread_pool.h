#pragma once
// A fixed set of std::threads, created once per render and reused for every parallel step of it
// (vertex stage, triangle set-up, tiles), so no step pays for thread creation. Work is handed out
// dynamically in chunks from an atomic counter, so uneven items balance across threads.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace farm {

// The one thread-count rule: `threads` threads when positive, else all hardware threads.
int resolve_thread_count(int threads);

class ThreadPool {
 public:
  // `threads` workers in all, the calling thread included (0 = all hardware threads).
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(workers_.size()) + 1; }

  // Calls body(begin, end, worker) for consecutive chunks of [0, count) of at most `grain` items,
  // on all threads, and returns when every chunk is done. `worker` is in [0, size()), so callers
  // can keep per-thread scratch space. The first exception thrown by a chunk is rethrown here
  // after the rest of the work has been abandoned.
  void parallel_for(std::size_t count, std::size_t grain,
                    const std::function<void(std::size_t, std::size_t, int)>& body);

 private:
  void worker_loop(int worker);
  void run_chunks(int worker);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::uint64_t generation_ = 0;  // bumped for each parallel_for
  int busy_ = 0;                  // workers still inside the current parallel_for
  bool stopping_ = false;

  // The current parallel_for.
  const std::function<void(std::size_t, std::size_t, int)>* body_ = nullptr;
  std::size_t count_ = 0, grain_ = 1;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr failure_;
};

}  // namespace farm
