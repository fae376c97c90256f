#include "server/scheduler/tile_worker.h"

#include "server/common/health_check.h"

namespace farm {

void TileCancel::cancel() {
  // The hook runs under the lock: set_hook(nullptr) then waits for it, so the call it cancels
  // (a ClientContext on the render thread's stack) is never touched after it has returned.
  // Cancelling outside the lock crashed a scheduler now and then (absl: "Mutex unlocked when
  // destroyed") when a job was cancelled as its call finished.
  std::lock_guard lock(mutex_);
  cancelled_ = true;
  if (hook_) hook_();
}

void TileCancel::set_hook(std::function<void()> hook) {
  std::lock_guard lock(mutex_);
  hook_ = std::move(hook);
  if (hook_ && cancelled_) hook_();
}

RemoteTileWorker::RemoteTileWorker(std::string address, WorkerLink link)
    : address_(std::move(address)), link_(std::move(link)) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  // A dead worker should be noticed and retried quickly, not after gRPC's default backoff.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  channel_ = open_channel(address_, link_.identity, args);
  stub_ = v1::Worker::NewStub(channel_);
}

grpc::Status RemoteTileWorker::render(const v1::RenderTileRequest& request, RenderedTiles& result,
                                      std::chrono::system_clock::time_point deadline,
                                      TileCancel& cancel) {
  std::optional<AssetGrants::Lease> lease;  // the worker may fetch the job's assets meanwhile
  if (link_.grants) lease.emplace(link_.grants->grant(link_.worker_name, request.job()));
  grpc::ClientContext context;
  context.set_deadline(deadline);
  cancel.set_hook([&context] { context.TryCancel(); });
  grpc::Status status = stub_->RenderTile(&context, request, &result.response);
  cancel.set_hook(nullptr);
  return status;
}

bool RemoteTileWorker::probe(std::chrono::milliseconds timeout) {
  // Connected is not enough: a stopped or hung process still accepts connections. It must answer.
  const auto deadline = std::chrono::system_clock::now() + timeout;
  return channel_->WaitForConnected(deadline) && check_health(channel_, deadline).serving();
}

}  // namespace farm
