#pragma once
// A `farm scheduler` process for tests and small client helpers over the generated
// farm.v1.Scheduler stub: upload a spec's assets, submit, poll or watch a job, fetch a result.
// Every wait is bounded.
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/common/client_identity.h"
#include "tests/support/background_process.h"

namespace farm::test {

// `farm scheduler --listen 127.0.0.1:0 --data-dir DIR <extra>`; waits for its "listening" line.
class SchedulerProcess {
 public:
  SchedulerProcess(const std::filesystem::path& data_dir, const std::vector<std::string>& extra_args);
  const std::string& address() const { return address_; }  // empty if it did not start
  BackgroundProcess& process() { return process_; }
  // With --http: the dashboard's "http://HOST:PORT" from its "dashboard on" line (waited for,
  // bounded); empty when it never came.
  std::string dashboard_url();

 private:
  BackgroundProcess process_;
  std::string address_;
};

// A scheduler (data under dir/data) and `workers` one-thread workers registered with it (caches
// under dir/w1, dir/w2, ...), as a user starts a small farm; `scheduler_args` are added to the
// scheduler's command line. `problem` says what did not start.
struct LocalFarm {
  std::unique_ptr<SchedulerProcess> scheduler;
  std::vector<std::unique_ptr<WorkerProcess>> workers;
  std::string problem;  // empty when all are up and registered
  const std::string& address() const { return scheduler->address(); }
};
LocalFarm start_local_farm(const std::filesystem::path& dir, int workers,
                           const std::vector<std::string>& scheduler_args = {});

std::unique_ptr<v1::Scheduler::Stub> scheduler_stub(const std::string& address);
// A stub calling as `identity` (its token, its TLS files).
std::unique_ptr<v1::Scheduler::Stub> scheduler_stub(const std::string& address, const ClientIdentity& identity);

// Uploads each (path in the job, file on disk) the scheduler lacks.
grpc::Status upload_assets(v1::Scheduler::Stub& stub,
                           const std::vector<std::pair<std::string, std::filesystem::path>>& files);

grpc::Status submit(v1::Scheduler::Stub& stub, const v1::JobSpec& spec, v1::Job& job,
                    int priority = 0);
std::optional<v1::Job> get_job(v1::Scheduler::Stub& stub, const std::string& id);

// Polls GetJob every 20 ms until `done(job)`; the last job seen, or nullopt on timeout.
std::optional<v1::Job> wait_for_job(v1::Scheduler::Stub& stub, const std::string& id,
                                    const std::function<bool(const v1::Job&)>& done,
                                    std::chrono::milliseconds timeout);

// WatchJob to the end (bounded by `timeout`): every event, in order. `subscribed` (when given) is
// called once the first event, the snapshot, has come: every later change reaches the watch.
std::vector<v1::JobEvent> watch_job(v1::Scheduler::Stub& stub, const std::string& id,
                                    std::chrono::milliseconds timeout, grpc::Status* status = nullptr,
                                    const std::function<void()>& subscribed = {});

// GetResult's bytes, written to `file`.
grpc::Status fetch_result(v1::Scheduler::Stub& stub, const std::string& id, v1::ResultKind kind,
                          const std::filesystem::path& file, std::optional<int> frame = std::nullopt);

}  // namespace farm::test
