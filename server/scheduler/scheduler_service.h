#pragma once
// farm.v1.Scheduler over gRPC: a thin adapter over the scheduler's front door (front_door.h).
// Each RPC authenticates its ServerContext to a Principal, makes one call of the front door, which
// checks the roles and ownership, and maps what it throws to a grpc::Status. What is gRPC's own
// stays here: the streams of WatchJob, GetResult, UploadAsset and GetAsset, and the watchdog that
// ends upload streams gone silent.
#include "proto/farm.grpc.pb.h"
#include "server/common/access_control.h"
#include "server/scheduler/assets/stream_watchdog.h"
#include "server/scheduler/front_door.h"

namespace farm {

class SchedulerService final : public v1::Scheduler::Service {
 public:
  explicit SchedulerService(SchedulerFrontDoor& front_door)
      : front_door_(front_door), uploads_(front_door.upload_idle_timeout()) {}

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
  grpc::Status SetJobLimits(grpc::ServerContext*, const v1::SetJobLimitsRequest*, v1::SetJobLimitsResponse*) override;
  grpc::Status AddDependencies(grpc::ServerContext*, const v1::AddDependenciesRequest*,
                               v1::AddDependenciesResponse*) override;
  grpc::Status RetryJob(grpc::ServerContext*, const v1::RetryJobRequest*, v1::RetryJobResponse*) override;
  grpc::Status DeleteJob(grpc::ServerContext*, const v1::DeleteJobRequest*, v1::DeleteJobResponse*) override;
  grpc::Status GetJobLog(grpc::ServerContext*, const v1::GetJobLogRequest*, v1::GetJobLogResponse*) override;
  grpc::Status ListWorkers(grpc::ServerContext*, const v1::ListWorkersRequest*, v1::ListWorkersResponse*) override;
  grpc::Status UploadAsset(grpc::ServerContext*, grpc::ServerReader<v1::UploadAssetRequest>*,
                           v1::UploadAssetResponse*) override;
  grpc::Status HasAssets(grpc::ServerContext*, const v1::HasAssetsRequest*, v1::HasAssetsResponse*) override;
  grpc::Status GetAsset(grpc::ServerContext*, const v1::GetAssetRequest*,
                        grpc::ServerWriter<v1::AssetChunk>*) override;
  grpc::Status PlanSubmission(grpc::ServerContext*, const v1::PlanSubmissionRequest*,
                              v1::PlanSubmissionResponse*) override;
  grpc::Status RegisterWorker(grpc::ServerContext*, const v1::RegisterWorkerRequest*,
                              v1::RegisterWorkerResponse*) override;
  grpc::Status Heartbeat(grpc::ServerContext*, const v1::HeartbeatRequest*, v1::HeartbeatResponse*) override;

 private:
  // The caller of `context` (ServiceError UNAUTHENTICATED when it presents no token the
  // scheduler knows).
  Principal caller(const grpc::ServerContext& context) const { return front_door_.access().authenticate(context); }

  SchedulerFrontDoor& front_door_;
  StreamWatchdog uploads_;  // UploadAsset streams that stop sending are ended
};

}  // namespace farm
