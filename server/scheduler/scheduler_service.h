#pragma once
// farm.v1.Scheduler over gRPC: a thin layer over SchedulerCore (jobs, dispatch, merge) and its
// AssetStore. Every RPC of proto/farm.proto's Scheduler service.
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/scheduler/scheduler_core.h"

namespace farm {

class SchedulerService final : public v1::Scheduler::Service {
 public:
  explicit SchedulerService(SchedulerCore& core) : core_(core) {}

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
  SchedulerCore& core_;
  std::mutex mutex_;
  std::map<std::string, std::string> registered_;  // worker address -> worker id
};

}  // namespace farm
