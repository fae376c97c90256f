#pragma once
// farm.v1.Scheduler over gRPC: a thin layer over SchedulerCore (jobs, dispatch, merge) and its
// AssetStore. Every RPC of proto/farm.proto's Scheduler service.
#include <filesystem>
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/access_control.h"
#include "server/common/client_identity.h"
#include "server/scheduler/assets/stream_watchdog.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

inline constexpr int kDefaultMaxPriority = 100;

// Who may call the scheduler, and how it calls the workers that register with it.
//   SubmitJob, UploadAsset, HasAssets      submit, admin
//   GetJob, WatchJob, GetResult, ListJobs  submit (own jobs; ListJobs lists only them), read, admin
//   CancelJob, PauseJob, SetPriority,      submit (own jobs), admin
//   RetryJob, DeleteJob
//   GetJobLog                              submit (own jobs), read, admin
//   ListWorkers                            read, admin
//   RegisterWorker, Heartbeat              worker, admin
//   GetAsset                               worker (assets of the calls it has been given), admin
// A priority above max_priority needs admin (SubmitJob, SetPriority).
struct SchedulerAccess {
  AccessControl access;             // default: every caller holds every role
  ClientIdentity worker_identity;   // token and TLS for calls to registered workers
  int max_priority = kDefaultMaxPriority;
};

class SchedulerService final : public v1::Scheduler::Service {
 public:
  explicit SchedulerService(SchedulerCore& core, SchedulerAccess access = {})
      : core_(core), access_(std::move(access)), uploads_(core.options().upload_idle_timeout) {}

  grpc::Status SubmitJob(grpc::ServerContext*, const v1::SubmitJobRequest*, v1::SubmitJobResponse*) override;
  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job*) override;
  grpc::Status ListJobs(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsResponse*) override;
  grpc::Status WatchJob(grpc::ServerContext*, const v1::WatchJobRequest*,
                        grpc::ServerWriter<v1::JobEvent>*) override;
  grpc::Status CancelJob(grpc::ServerContext*, const v1::CancelJobRequest*, v1::CancelJobResponse*) override;
  grpc::Status GetResult(grpc::ServerContext*, const v1::GetResultRequest*,
                         grpc::ServerWriter<v1::FileChunk>*) override;
  grpc::Status PauseJob(grpc::ServerContext*, const v1::PauseJobRequest*, v1::PauseJobResponse*) override;
  grpc::Status SetPriority(grpc::ServerContext*, const v1::SetPriorityRequest*, v1::SetPriorityResponse*) override;
  grpc::Status RetryJob(grpc::ServerContext*, const v1::RetryJobRequest*, v1::RetryJobResponse*) override;
  grpc::Status DeleteJob(grpc::ServerContext*, const v1::DeleteJobRequest*, v1::DeleteJobResponse*) override;
  grpc::Status GetJobLog(grpc::ServerContext*, const v1::GetJobLogRequest*, v1::GetJobLogResponse*) override;
  grpc::Status ListWorkers(grpc::ServerContext*, const v1::ListWorkersRequest*, v1::ListWorkersResponse*) override;
  grpc::Status UploadAsset(grpc::ServerContext*, grpc::ServerReader<v1::UploadAssetRequest>*,
                           v1::UploadAssetResponse*) override;
  grpc::Status HasAssets(grpc::ServerContext*, const v1::HasAssetsRequest*, v1::HasAssetsResponse*) override;
  grpc::Status GetAsset(grpc::ServerContext*, const v1::GetAssetRequest*,
                        grpc::ServerWriter<v1::AssetChunk>*) override;
  grpc::Status RegisterWorker(grpc::ServerContext*, const v1::RegisterWorkerRequest*,
                              v1::RegisterWorkerResponse*) override;
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*, v1::HeartbeatResponse*) override;

  // The RPCs about jobs and workers, for a caller that is already authenticated (`who`): the gRPC
  // handlers above call them, and so does the dashboard's HTTP API (http/dashboard_server.h), so
  // that both check the same roles and ownership in the same place. ServiceError or InputError
  // as the RPC would return them.
  v1::Job get_job(const Principal& who, const std::string& job_id) const;
  v1::ListJobsResponse list_jobs(const Principal& who, const v1::ListJobsRequest& request) const;
  v1::Job cancel_job(const Principal& who, const std::string& job_id);
  v1::Job pause_job(const Principal& who, const std::string& job_id, bool paused);
  v1::Job set_priority(const Principal& who, const std::string& job_id, int priority);
  v1::RetryJobResponse retry_job(const Principal& who, const std::string& job_id);
  v1::DeleteJobResponse delete_job(const Principal& who, const std::string& job_id);
  v1::GetJobLogResponse job_log(const Principal& who, const v1::GetJobLogRequest& request) const;
  v1::ListWorkersResponse list_workers(const Principal& who) const;
  // The file GetResult streams.
  std::filesystem::path result_file(const Principal& who, const v1::GetResultRequest& request) const;
  // `who` may watch `job_id` (WatchJob's check): the job as it is now.
  v1::Job watchable_job(const Principal& who, const std::string& job_id) const;

 private:
  // The job `job_id` if `who` may see it: its owner, or a caller holding `any_job` roles.
  // ServiceError NOT_FOUND or PERMISSION_DENIED.
  v1::Job visible_job(const Principal& who, const std::string& job_id, Roles any_job, const char* rpc) const;
  // Refuses a caller without admin a priority above max_priority (`what`: the action, for the message).
  void check_priority(const Principal& who, int priority, const char* what) const;

  struct Registered {
    std::string worker_id;
    std::string principal;  // the token name that registered it
  };

  SchedulerCore& core_;
  const SchedulerAccess access_;
  std::mutex mutex_;
  std::map<std::string, Registered> registered_;  // by worker address
  // Who registered each worker id now in registered_: a heartbeat, every second from every
  // worker, finds its registrant in one look-up.
  std::map<std::string, std::string> registrant_of_;
  StreamWatchdog uploads_;  // UploadAsset streams that stop sending are ended
};

}  // namespace farm
