#include "server/bench/loopback_farm.h"

#include <fmt/format.h>

#include <chrono>
#include <stdexcept>

#include "server/bench/bench_support.h"

namespace farm::bench {

namespace {
constexpr auto kStartTimeout = std::chrono::seconds(30);
}  // namespace

LoopbackFarm::LoopbackFarm(const std::filesystem::path& dir, int workers, int tiles_per_worker, int batch_ms,
                           int worker_threads) {
  const std::string farm = self_binary();
  scheduler_ = std::make_unique<ChildProcess>(std::vector<std::string>{
      farm, "scheduler", "--listen", "127.0.0.1:0", "--data-dir", (dir / "scheduler").string(), "--tiles-per-worker",
      std::to_string(tiles_per_worker), "--batch-ms", std::to_string(batch_ms)});
  address_ = wait_for_listening(*scheduler_, "scheduler", kStartTimeout);
  if (address_.empty()) throw std::runtime_error("the scheduler did not start: " + scheduler_->output());
  for (int i = 0; i < workers; ++i) {
    // Registered workers fetch their assets from the scheduler, like a real deployment.
    auto worker = std::make_unique<ChildProcess>(std::vector<std::string>{
        farm, "worker", "--listen", "127.0.0.1:0", "--scheduler", address_, "--cache-dir",
        (dir / fmt::format("worker{}", i)).string(), "--threads", std::to_string(worker_threads)});
    if (wait_for_listening(*worker, "worker", kStartTimeout).empty()) {
      throw std::runtime_error("a worker did not start: " + worker->output());
    }
    workers_.push_back(std::move(worker));
  }
  // Wait until every worker has registered: a job then sees all of them from its first tile.
  if (!scheduler_->wait_for_line(fmt::format("worker w{}-", workers), kStartTimeout)) {
    throw std::runtime_error("the workers did not register: " + scheduler_->output());
  }
}

}  // namespace farm::bench
