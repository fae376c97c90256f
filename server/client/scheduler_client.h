#pragma once
// The client side of farm.v1.Scheduler, as `farm submit/status/watch/cancel/fetch` use it: one
// blocking call per operation, gRPC failures turned into exceptions that say what to do.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_connection.h"
#include "server/common/job_state.h"

namespace farm {

// Which jobs list() asks for; what is left empty keeps every job (ListJobsRequest).
struct JobListing {
  std::vector<v1::JobState> states = {};
  std::string name = {};       // a glob: `*`, `?`; case-insensitive
  std::string id_prefix = {};  // lowercase hex
  std::size_t limit = 0;       // at most this many, newest first; 0: every one
};

class SchedulerClient {
 public:
  explicit SchedulerClient(SchedulerConnection connection);
  // A scheduler on this machine that asks for no token (tests, benchmarks).
  explicit SchedulerClient(std::string address) : SchedulerClient(SchedulerConnection{std::move(address), {}}) {}

  const std::string& address() const { return address_; }

  // Uploads the files the scheduler lacks (HasAssets first); returns how many were sent.
  std::size_t upload_missing(const JobSubmission& submission);
  v1::Job submit(const JobSubmission& submission, int priority);
  // With the rest of the request (priority, dependencies, caps) as `request` has it.
  v1::Job submit(const JobSubmission& submission, v1::SubmitJobRequest request);
  v1::Job get(const std::string& job_id);
  // The jobs `listing` asks for, newest first; `more` (when given) says whether others beyond
  // its limit match too.
  std::vector<v1::Job> list(const JobListing& listing = {}, bool* more = nullptr);
  // The id of the one job whose id starts with `id_or_prefix` (a whole id is its own prefix).
  // ServiceError NOT_FOUND when none does; InputError naming a few when several do.
  std::string resolve_job_id(const std::string& id_or_prefix);
  std::vector<std::string> resolve_job_ids(const std::vector<std::string>& ids_or_prefixes);
  // Streams the job's events to `on_event` until it reaches a final state; returns that job.
  v1::Job watch(const std::string& job_id, const std::function<void(const v1::JobEvent&)>& on_event);
  v1::Job cancel(const std::string& job_id);
  // Job management (PauseJob, SetPriority, RetryJob, DeleteJob, GetJobLog, ListWorkers).
  v1::Job pause(const std::string& job_id, bool paused);
  v1::Job set_priority(const std::string& job_id, int priority);
  // SetJobLimits: each cap given replaces the job's (0: none).
  v1::Job set_limits(const std::string& job_id, std::optional<std::uint32_t> max_workers,
                     std::optional<std::uint32_t> max_units_in_flight);
  v1::Job add_dependencies(const std::string& job_id, const std::vector<std::string>& after,
                           const std::vector<std::string>& after_any);
  v1::RetryJobResponse retry(const std::string& job_id);
  v1::DeleteJobResponse remove(const std::string& job_id);
  // The job's whole event log, page after page.
  std::vector<v1::JobLogEntry> log(const std::string& job_id);
  std::vector<v1::WorkerInfo> workers();
  // Downloads a result to the file `where(suggested name)` returns (the name the scheduler
  // suggests, a plain file name, possibly empty), through a temporary file, checking its size and
  // SHA-256; returns the file.
  using Destination = std::function<std::filesystem::path(const std::string& suggested_name)>;
  // `frame`: that frame of a job with frames (as soon as it is merged); none: the job's first.
  std::filesystem::path fetch(const std::string& job_id, v1::ResultKind kind, const Destination& where,
                              std::optional<int> frame = std::nullopt);

 private:
  // One unary call; failures thrown as throw_for_status says.
  template <typename Response, typename Request, typename Method>
  Response call(Method method, const Request& request, const char* what);

  std::string address_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
};

// Status codes that mean the request was wrong (exit code 2) become InputError; an unreachable
// scheduler a ServiceError(UNAVAILABLE) that says where it was looked for; a refused caller
// (UNAUTHENTICATED, PERMISSION_DENIED) a ServiceError with the scheduler's reason; the rest a
// runtime_error with the scheduler's message.
[[noreturn]] void throw_for_status(const grpc::Status& status, const std::string& what,
                                   const std::string& address);

}  // namespace farm
