// The render thread pool: every item once, errors surface, loops nest, and a loop can be
// abandoned. No sleeps: threads are held and released with promises.
#include "renderer/util/thread_pool.h"

#include "renderer/util/frame_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <future>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

namespace farm {
namespace {

TEST(ThreadPool, ParallelForVisitsEveryItemOnceOnAThreadOfThePool) {
  ThreadPool pool(3);
  ASSERT_EQ(pool.size(), 3);
  std::vector<std::atomic<int>> seen(1000);
  std::atomic<bool> bad_worker{false};
  pool.parallel_for(seen.size(), 7, [&](std::size_t begin, std::size_t end, int worker) {
    if (worker < 0 || worker >= pool.size()) bad_worker = true;
    for (std::size_t i = begin; i < end; ++i) ++seen[i];
  });
  for (const auto& s : seen) ASSERT_EQ(s.load(), 1);
  EXPECT_FALSE(bad_worker);
}

TEST(ThreadPool, TheFirstExceptionIsRethrownAndTheRestSkipped) {
  ThreadPool pool(2);
  std::atomic<int> ran{0};
  // Every chunk but the throwing one is held until the failure is recorded, so the outcome does
  // not depend on which thread the OS runs first (a preempted thrower once let the other thread
  // run all 9999 chunks before the skip took effect).
  std::promise<std::shared_ptr<ThreadPool::Work>> work_promise;
  const std::shared_future<std::shared_ptr<ThreadPool::Work>> work_future = work_promise.get_future().share();
  const std::shared_ptr<ThreadPool::Work> work =
      pool.start(10000, 1, [&](std::size_t begin, std::size_t, int) {
        ++ran;
        if (begin == 0) throw std::runtime_error("chunk 0");
        const std::shared_ptr<ThreadPool::Work>& self = work_future.get();
        while (!self->failure()) std::this_thread::yield();
      });
  work_promise.set_value(work);
  work->wait();
  ASSERT_TRUE(work->failure());
  // Chunk 0, plus at most the one chunk each other thread had claimed before the failure.
  EXPECT_LE(ran.load(), pool.size());
  // parallel_for rethrows the chunk's exception to its caller.
  EXPECT_THROW(pool.parallel_for(100, 1, [](std::size_t begin, std::size_t, int) {
                 if (begin == 0) throw std::runtime_error("chunk 0");
               }),
               std::runtime_error);
  // The pool still works afterwards.
  std::atomic<int> after{0};
  pool.parallel_for(10, 1, [&](std::size_t, std::size_t, int) { ++after; });
  EXPECT_EQ(after.load(), 10);
}

TEST(ThreadPool, ALoopStartedFromAPoolThreadNestsWithoutDeadlock) {
  ThreadPool pool(1);  // the one thread runs the outer chunk and must help with the inner loop
  std::atomic<int> inner{0};
  pool.parallel_for(2, 1, [&](std::size_t, std::size_t, int) {
    pool.parallel_for(50, 1, [&](std::size_t, std::size_t, int) { ++inner; });
  });
  EXPECT_EQ(inner.load(), 100);
}

// Two calls of one frame on a pool of two threads, each asking FrameCache for the frame's set-up
// from pool work (as TileRenderer does): the one that waits for the other's build runs the build's
// loop with it. Counted, not timed: each of the build's two chunks waits until both have started,
// which happens only when both threads run them (without the help, the builder would run the
// second chunk only after the first gave up waiting, and one thread would have run both).
TEST(ThreadPool, APoolThreadWaitingForAFrameBuildHelpsRunIt) {
  ThreadPool pool(2);
  FrameCache cache;
  CancelFlag never;
  std::mutex mutex;
  std::condition_variable both_started;
  int started = 0;
  std::set<int> builders;
  int builds = 0;
  const auto build = [&] {
    ++builds;
    pool.parallel_for(2, 1, [&](std::size_t, std::size_t, int worker) {
      std::unique_lock lock(mutex);
      builders.insert(worker);
      ++started;
      both_started.notify_all();
      both_started.wait_for(lock, std::chrono::seconds(20), [&] { return started == 2; });
    });
    return std::make_shared<const int>(42);
  };
  std::atomic<int> answers{0};
  const auto call = [&](std::size_t, std::size_t, int) {
    if (*cache.get_or_build<int>("frame", never, build) == 42) ++answers;
  };
  const std::shared_ptr<ThreadPool::Work> first = pool.start(1, 1, call), second = pool.start(1, 1, call);
  first->wait();
  second->wait();
  EXPECT_EQ(answers.load(), 2);
  EXPECT_EQ(builds, 1);
  EXPECT_EQ(builders, (std::set<int>{0, 1}));
}

// A helping thread runs chunks of the loops of the build it waits for (tagged) and of no other:
// it may be inside a chunk of another loop, holding that loop's per-thread scratch, which a chunk
// of the same loop run on it would overwrite (render_frame's tile buffers: a heap corruption).
TEST(ThreadPool, AHelperRunsOnlyTheLoopsOfTheBuildItWaitsFor) {
  ThreadPool pool(1);
  int tag = 0;
  std::mutex mutex;
  std::condition_variable cv;
  bool tagged_started = false, tagged_ran = false, tagged_ran_during_help = false, untagged_ran_during_help = false;
  std::atomic<bool> second_item_ran{false};
  std::shared_ptr<ThreadPool::Work> tagged;
  const auto untagged = pool.start(2, 1, [&](std::size_t begin, std::size_t, int) {
    if (begin == 1) {
      second_item_ran = true;
      return;
    }
    {
      std::unique_lock lock(mutex);
      cv.wait_for(lock, std::chrono::seconds(20), [&] { return tagged_started; });
    }
    // One pool thread, busy here: the other loops can run only if this call runs them.
    for (int i = 0; i < 3; ++i) ThreadPool::help_while_waiting(&tag, std::chrono::milliseconds(1));
    std::lock_guard lock(mutex);
    untagged_ran_during_help = second_item_ran.load();
    tagged_ran_during_help = tagged_ran;
  });
  {
    const ThreadPool::LoopTag loops(&tag);
    tagged = pool.start(1, 1, [&](std::size_t, std::size_t, int) {
      std::lock_guard lock(mutex);
      tagged_ran = true;
    });
  }
  {
    std::lock_guard lock(mutex);
    tagged_started = true;
  }
  cv.notify_all();
  untagged->wait();
  tagged->wait();
  EXPECT_TRUE(tagged_ran_during_help);
  EXPECT_FALSE(untagged_ran_during_help);
  EXPECT_TRUE(second_item_ran.load());
}

// Off the pool, a waiter has nothing to help with: it is told so at once.
TEST(ThreadPool, HelpingIsOnlyForPoolThreads) {
  int tag = 0;
  EXPECT_FALSE(ThreadPool::help_while_waiting(&tag, std::chrono::milliseconds(1)));
  ThreadPool pool(1);
  std::atomic<bool> helped{false};
  pool.parallel_for(1, 1, [&](std::size_t, std::size_t, int) {
    helped = ThreadPool::help_while_waiting(&tag, std::chrono::milliseconds(1));
  });
  EXPECT_TRUE(helped.load());
}

TEST(ThreadPool, ConcurrentCallersEachGetTheirLoopDone) {
  ThreadPool pool(2);
  std::atomic<int> total{0};
  std::vector<std::thread> callers;
  for (int c = 0; c < 4; ++c) {
    callers.emplace_back([&] {
      pool.parallel_for(500, 3, [&](std::size_t b, std::size_t e, int) { total += static_cast<int>(e - b); });
    });
  }
  for (std::thread& t : callers) t.join();
  EXPECT_EQ(total.load(), 2000);
}

TEST(ThreadPool, ACancelledLoopSkipsWhatHasNotStartedAndItsWaiterReturns) {
  ThreadPool pool(1);
  std::promise<void> started, release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> ran{0};
  const auto work = pool.start(100, 1, [&](std::size_t begin, std::size_t, int) {
    ++ran;
    if (begin == 0) {
      started.set_value();
      released.wait();  // the pool's only thread is held inside the first chunk
    }
  });
  started.get_future().wait();
  EXPECT_FALSE(work->wait_for(std::chrono::milliseconds(0)));
  work->cancel();
  release.set_value();
  work->wait();
  EXPECT_EQ(ran.load(), 1);  // only the chunk that had started
  EXPECT_EQ(work->failure(), nullptr);
}

TEST(ThreadPool, LoopsQueuedWhenThePoolIsDestroyedAreSkippedNotLost) {
  std::shared_ptr<ThreadPool::Work> queued;
  std::atomic<int> ran{0};
  {
    ThreadPool pool(1);
    std::promise<void> started, release;
    std::shared_future<void> released = release.get_future().share();
    const auto busy = pool.start(1, 1, [&](std::size_t, std::size_t, int) {
      started.set_value();
      released.wait();
    });
    started.get_future().wait();
    queued = pool.start(10, 1, [&](std::size_t, std::size_t, int) { ++ran; });
    release.set_value();
    busy->wait();
  }  // the queued loop may or may not have run by now; either way it has ended
  EXPECT_TRUE(queued->wait_for(std::chrono::milliseconds(0)));
  EXPECT_TRUE(ran.load() == 0 || ran.load() == 10);
}

}  // namespace
}  // namespace farm
