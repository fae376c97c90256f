#include "renderer/util/thread_pool.h"

#include <algorithm>
#include <utility>

namespace farm {

namespace {

// Which pool, if any, the current thread belongs to, and its index there: a pool thread that
// starts a loop works on it instead of blocking one of the threads the loop needs.
thread_local ThreadPool* t_pool = nullptr;
thread_local int t_index = -1;
// The LoopTag in force on this thread.
thread_local const void* t_tag = nullptr;

}  // namespace

int resolve_thread_count(int threads) {
  if (threads > 0) return threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

ThreadPool::Work::Work(std::size_t count, std::size_t grain, Body body)
    : count_(count),
      grain_(std::max<std::size_t>(1, grain)),
      chunks_((count + grain_ - 1) / grain_),
      body_(std::move(body)),
      tag_(t_tag) {}

ThreadPool::LoopTag::LoopTag(const void* tag) : previous_(std::exchange(t_tag, tag)) {}

ThreadPool::LoopTag::~LoopTag() { t_tag = previous_; }

void ThreadPool::Work::run_chunks(int worker) {
  while (run_one(worker)) {
  }
}

bool ThreadPool::Work::run_one(int worker) {
  const std::size_t begin = next_.fetch_add(grain_);
  if (begin >= count_) return false;
  std::exception_ptr failure;
  if (!cancelled_.load(std::memory_order_relaxed)) {
    try {
      body_(begin, std::min(count_, begin + grain_), worker);
    } catch (...) {
      failure = std::current_exception();
      cancelled_ = true;  // the rest is skipped
    }
  }
  std::lock_guard lock(mutex_);
  if (failure && !failure_) failure_ = failure;
  if (++chunks_done_ == chunks_) finished_.notify_all();
  return true;
}

bool ThreadPool::Work::wait_for(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return finished_.wait_for(lock, timeout, [this] { return chunks_done_ == chunks_; });
}

void ThreadPool::Work::wait() {
  std::unique_lock lock(mutex_);
  finished_.wait(lock, [this] { return chunks_done_ == chunks_; });
}

std::exception_ptr ThreadPool::Work::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

ThreadPool::ThreadPool(int threads) {
  const int n = resolve_thread_count(threads);
  threads_.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) threads_.emplace_back([this, i] { thread_loop(i); });
}

ThreadPool::~ThreadPool() {
  std::deque<std::shared_ptr<Work>> left;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    left.swap(queue_);
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
  // Loops nobody will run: skip their chunks here, so that whoever waits on them returns.
  for (const std::shared_ptr<Work>& work : left) {
    work->cancel();
    work->run_chunks(0);
  }
}

std::shared_ptr<ThreadPool::Work> ThreadPool::start(std::size_t count, std::size_t grain, Body body) {
  auto work = std::make_shared<Work>(count, grain, std::move(body));
  if (work->chunks_ == 0) return work;  // nothing to do: already finished
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(work);
  }
  wake_.notify_all();
  return work;
}

void ThreadPool::parallel_for(std::size_t count, std::size_t grain, const Body& body) {
  const std::shared_ptr<Work> work = start(count, grain, body);
  if (t_pool == this) work->run_chunks(t_index);  // nested: help rather than block a thread
  work->wait();
  if (const std::exception_ptr failure = work->failure()) std::rethrow_exception(failure);
}

bool ThreadPool::help_while_waiting(const void* tag, std::chrono::milliseconds wait) {
  if (t_pool == nullptr) return false;
  t_pool->help(tag, t_index, wait);
  return true;
}

void ThreadPool::help(const void* tag, int index, std::chrono::milliseconds wait) {
  std::shared_ptr<Work> work;
  {
    std::unique_lock lock(mutex_);
    const auto claimable = [&] {
      const auto it = std::find_if(queue_.begin(), queue_.end(),
                                   [&](const auto& w) { return w->tag_ == tag && !w->exhausted(); });
      if (it != queue_.end()) work = *it;
      return work != nullptr || stopping_;
    };
    if (!claimable()) wake_.wait_for(lock, wait, claimable);
  }
  if (work) work->run_one(index);  // the queue is tidied by the thread that finds it exhausted
}

void ThreadPool::thread_loop(int index) {
  t_pool = this;
  t_index = index;
  for (;;) {
    std::shared_ptr<Work> work;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      work = queue_.front();
    }
    work->run_chunks(index);
    // Nothing left to claim: out of the queue (another thread may have taken it out already).
    std::lock_guard lock(mutex_);
    const auto it = std::find(queue_.begin(), queue_.end(), work);
    if (it != queue_.end()) queue_.erase(it);
  }
}

}  // namespace farm
