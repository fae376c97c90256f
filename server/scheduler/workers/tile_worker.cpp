#include "server/scheduler/workers/tile_worker.h"

#include <fmt/format.h>

#include <list>
#include <map>
#include <utility>

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

namespace {

std::shared_ptr<grpc::Channel> make_channel(const std::string& address, const ClientIdentity& identity) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(-1);
  // A dead worker should be noticed and retried quickly, not after gRPC's default backoff.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
  return open_channel(address, identity, args);
}

// One channel per worker address, whatever number of times a worker registers there. gRPC (1.51,
// Debian 12) keeps a connection's transport when its channel is destroyed mid-connection, some
// kilobytes each time: a worker registering again and again, each time with a channel of its
// own, grew the scheduler without bound. So the channel of an address outlives its worker while
// the address is among the last few used, and is handed to the next worker there. Channels are
// kept by address and identity (token and TLS files): a channel carries its caller's credentials.
class ChannelPool {
 public:
  std::shared_ptr<grpc::Channel> get(const std::string& address, const ClientIdentity& identity) {
    const std::string key = fmt::format("{}\n{}\n{}\n{}\n{}\n{}", address, identity.token, identity.tls,
                                        identity.tls_files.cert.string(), identity.tls_files.key.string(),
                                        identity.tls_files.ca.string());
    std::lock_guard lock(mutex_);
    std::shared_ptr<grpc::Channel> channel;
    if (auto it = channels_.find(key); it != channels_.end()) channel = it->second.lock();
    if (channel) {
      // The worker is back: connect now rather than when the backoff of its last failure ends.
      grpc::experimental::ChannelResetConnectionBackoff(channel.get());
    } else {
      channel = make_channel(address, identity);
      std::erase_if(channels_, [](const auto& entry) { return entry.second.expired(); });
      channels_[key] = channel;
    }
    std::erase_if(recent_, [&](const auto& entry) { return entry.first == key; });
    recent_.emplace_front(key, channel);
    if (recent_.size() > kRecent) recent_.pop_back();
    return channel;
  }

 private:
  static constexpr std::size_t kRecent = 16;
  std::mutex mutex_;
  std::map<std::string, std::weak_ptr<grpc::Channel>> channels_;  // every address (and identity) in use
  std::list<std::pair<std::string, std::shared_ptr<grpc::Channel>>> recent_;  // most recent first
};

ChannelPool& channel_pool() {
  static ChannelPool pool;
  return pool;
}

}  // namespace

RemoteTileWorker::RemoteTileWorker(std::string address, WorkerLink link)
    : address_(std::move(address)), link_(std::move(link)),
      channel_(channel_pool().get(address_, link_.identity)), stub_(v1::Worker::NewStub(channel_)) {}

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

bool RemoteTileWorker::connected() { return channel_->GetState(true) == GRPC_CHANNEL_READY; }

bool RemoteTileWorker::probe(std::chrono::milliseconds timeout) {
  // Connected is not enough: a stopped or hung process still accepts connections. It must answer.
  const auto deadline = std::chrono::system_clock::now() + timeout;
  return channel_->WaitForConnected(deadline) && check_health(channel_, deadline).serving();
}

}  // namespace farm
