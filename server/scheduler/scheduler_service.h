#pragma once
// farm.v1.Scheduler over gRPC: a thin layer over SchedulerCore (jobs, dispatch, merge) and its
// AssetStore. Every RPC of proto/farm.proto's Scheduler service.
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/access_control.h"
#include "server/common/client_identity.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

inline constexpr int kDefaultMaxPriority = 100;

// Who may call the scheduler, and how it calls the workers that register with it.
//   SubmitJob, UploadAsset, HasAssets      submit, admin
//   GetJob, WatchJob, GetResult, ListJobs  submit (own jobs; ListJobs lists only them), read, admin
//   CancelJob                              submit (own jobs), admin
//   RegisterWorker, Heartbeat              worker, admin
//   GetAsset                               worker (assets of the calls it has been given), admin
// A priority above max_priority needs admin.
struct SchedulerAccess {
  AccessControl access;             // default: every caller holds every role
  ClientIdentity worker_identity;   // token and TLS for calls to registered workers
  int max_priority = kDefaultMaxPriority;
};

class SchedulerService final : public v1::Scheduler::Service {
 public:
  explicit SchedulerService(SchedulerCore& core, SchedulerAccess access = {})
      : core_(core), access_(std::move(access)) {}

  grpc::Status SubmitJob(grpc::ServerContext*, const v1::SubmitJobRequest*, v1::SubmitJobResponse*) override;
  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job*) override;
  grpc::Status ListJobs(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsResponse*) override;
  grpc::Status WatchJob(grpc::ServerContext*, const v1::WatchJobRequest*,
                        grpc::ServerWriter<v1::JobEvent>*) override;
  grpc::Status CancelJob(grpc::ServerContext*, const v1::CancelJobRequest*, v1::CancelJobResponse*) override;
  grpc::Status GetResult(grpc::ServerContext*, const v1::GetResultRequest*,
                         grpc::ServerWriter<v1::FileChunk>*) override;
  grpc::Status UploadAsset(grpc::ServerContext*, grpc::ServerReader<v1::UploadAssetRequest>*,
                           v1::UploadAssetResponse*) override;
  grpc::Status HasAssets(grpc::ServerContext*, const v1::HasAssetsRequest*, v1::HasAssetsResponse*) override;
  grpc::Status GetAsset(grpc::ServerContext*, const v1::GetAssetRequest*,
                        grpc::ServerWriter<v1::AssetChunk>*) override;
  grpc::Status RegisterWorker(grpc::ServerContext*, const v1::RegisterWorkerRequest*,
                              v1::RegisterWorkerResponse*) override;
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*, v1::HeartbeatResponse*) override;

 private:
  // The job `job_id` if `who` may see it: its owner, or a caller holding `any_job` roles.
  // ServiceError NOT_FOUND or PERMISSION_DENIED.
  v1::Job visible_job(const Principal& who, const std::string& job_id, Roles any_job, const char* rpc) const;

  struct Registered {
    std::string worker_id;
    std::string principal;  // the token name that registered it
  };

  SchedulerCore& core_;
  const SchedulerAccess access_;
  std::mutex mutex_;
  std::map<std::string, Registered> registered_;  // by worker address
};

}  // namespace farm
