#pragma once
// A scheduler and workers on loopback, each its own `farm` process as a user runs them, for the
// benchmarks that measure the farm over the network (bench farm, bench regress).
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/child_process.h"

namespace farm::bench {

class LoopbackFarm {
 public:
  // Starts `farm scheduler` with its data dir `data_dir` (empty: dir/scheduler) and its job store
  // `store` (a postgresql:// URL, or empty for SQLite in the data dir), and `workers` registered
  // workers with `worker_threads` threads each (0: all cores) under dir; returns once every
  // worker has registered. Two farms given one store and one data dir are two schedulers of one
  // farm. Throws std::runtime_error with the process's output when one does not start.
  LoopbackFarm(const std::filesystem::path& dir, int workers, int tiles_per_worker, int batch_ms, int worker_threads,
               const std::string& store = {}, const std::filesystem::path& data_dir = {});
  const std::string& address() const { return address_; }

 private:
  std::unique_ptr<ChildProcess> scheduler_;
  std::vector<std::unique_ptr<ChildProcess>> workers_;
  std::string address_;
};

// What `farm submit --wait` does up to the download: uploads what the scheduler lacks, submits,
// follows the job to its end. Returns the job (SUCCEEDED; std::runtime_error otherwise) and the
// seconds it all took.
std::pair<v1::Job, double> submit_and_wait(SchedulerClient& client, const JobSubmission& submission);

}  // namespace farm::bench
