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
                           int worker_threads, const std::string& store, const std::filesystem::path& data_dir) {
  const std::string farm = self_binary();
  std::vector<std::string> args{farm, "scheduler", "--listen", "127.0.0.1:0", "--data-dir",
                                (data_dir.empty() ? dir / "scheduler" : data_dir).string(),
                                "--tiles-per-worker", std::to_string(tiles_per_worker), "--batch-ms",
                                std::to_string(batch_ms)};
  if (!store.empty()) args.insert(args.end(), {"--store", store});
  scheduler_ = std::make_unique<ChildProcess>(args);
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

std::pair<v1::Job, double> submit_and_wait(SchedulerClient& client, const JobSubmission& submission) {
  const std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  client.upload_missing(submission);
  const v1::Job job = client.submit(submission, 0);
  const v1::Job last = client.watch(job.job_id(), {});
  if (last.state() != v1::JOB_STATE_SUCCEEDED) {
    throw std::runtime_error(fmt::format("job {} {}: {}", job.job_id(), to_string(last.state()), last.failure_reason()));
  }
  return {last, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

}  // namespace farm::bench
