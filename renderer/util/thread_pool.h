#pragma once
// The one pool of render threads: a fixed set of std::threads created once (per render, or per
// worker process) and reused for every parallel step (vertex stage, triangle set-up, tiles,
// sub-tiles of concurrent RenderTile calls), so no step pays for thread creation.
//
// Work is a parallel loop over [0, count) in chunks claimed from an atomic counter, so uneven
// items balance across threads. Several loops may be in flight at once (a worker's concurrent
// calls): the threads serve them first come, first served. A loop can be started and waited for
// with a timeout, or cancelled (its chunks not yet started are skipped), which lets a caller stop
// waiting the moment its client gives up. A pool thread that starts a loop of its own (nested
// parallelism) works on it while it waits, so nesting never deadlocks.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace farm {

// The one thread-count rule: `threads` threads when positive, else all hardware threads.
int resolve_thread_count(int threads);

class ThreadPool {
 public:
  using Body = std::function<void(std::size_t begin, std::size_t end, int worker)>;

  // One parallel loop in flight.
  class Work {
   public:
    Work(std::size_t count, std::size_t grain, Body body);
    // True once every chunk has finished or been skipped; false when `timeout` passed first.
    bool wait_for(std::chrono::milliseconds timeout);
    void wait();
    // Chunks not yet started are skipped; those running finish.
    void cancel() { cancelled_ = true; }
    // The first exception a chunk threw (the chunks after it are skipped), or null.
    std::exception_ptr failure() const;

   private:
    friend class ThreadPool;
    // Claims and runs (or skips) chunks until none is left to claim.
    void run_chunks(int worker);
    // Claims and runs (or skips) one chunk; false when none was left to claim.
    bool run_one(int worker);
    bool exhausted() const { return next_.load() >= count_; }

    const std::size_t count_, grain_, chunks_;
    const Body body_;
    const void* const tag_;  // the LoopTag of the thread that started it, or null
    std::atomic<std::size_t> next_{0};
    std::atomic<bool> cancelled_{false};
    mutable std::mutex mutex_;  // guards the two below
    std::condition_variable finished_;
    std::size_t chunks_done_ = 0;
    std::exception_ptr failure_;
  };

  // `threads` threads of its own (0 = all hardware threads). A caller that is not one of them
  // waits while they work.
  explicit ThreadPool(int threads);
  // Skips the chunks of loops still queued and joins the threads.
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return static_cast<int>(threads_.size()); }

  // Queues body(begin, end, worker) for consecutive chunks of [0, count) of at most `grain`
  // items and returns at once. `worker` is the index in [0, size()) of the thread running the
  // chunk, so callers can keep per-thread scratch space. The body is kept until the work ends.
  std::shared_ptr<Work> start(std::size_t count, std::size_t grain, Body body);

  // start() and wait; rethrows the first exception a chunk threw, after the rest was skipped.
  void parallel_for(std::size_t count, std::size_t grain, const Body& body);

  // Loops started on this thread while a LoopTag lives carry its tag (FrameCache: the loops of
  // one frame's set-up, tagged by its entry).
  class LoopTag {
   public:
    explicit LoopTag(const void* tag);
    ~LoopTag();
    LoopTag(const LoopTag&) = delete;
    LoopTag& operator=(const LoopTag&) = delete;

   private:
    const void* previous_;
  };

  // For a thread that waits on something another thread's loops are making (FrameCache: a
  // frame's set-up, built by another call): on a thread of a pool, runs one chunk of that pool's
  // queued loops tagged `tag` and returns true, or waits up to `wait` for one and returns true;
  // on any other thread returns false at once. Two calls of one frame used to start its set-up
  // on both of a worker's two threads, the second blocked waiting for the first, which built the
  // frame alone: 40 ms of the 100-cow grid's set-up on one thread. Only the tagged loops: the
  // waiting thread may be inside a chunk of another loop holding that loop's per-thread scratch
  // (render_frame's tile buffer of its worker index), which a chunk of the same loop run here
  // would overwrite.
  static bool help_while_waiting(const void* tag, std::chrono::milliseconds wait);

 private:
  void thread_loop(int index);
  // help_while_waiting on one of this pool's threads.
  void help(const void* tag, int index, std::chrono::milliseconds wait);

  std::mutex mutex_;  // guards the queue and stopping_
  std::condition_variable wake_;
  std::deque<std::shared_ptr<Work>> queue_;  // loops with chunks left to claim, oldest first
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace farm
