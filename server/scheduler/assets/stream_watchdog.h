#pragma once
// Ends client streams that stop sending (issue #32): an UploadAsset stream that announced its size
// and then went quiet held its share of the asset quota, and a thread, for ever, since a
// synchronous gRPC server's Read waits as long as the client keeps the stream open. Each stream
// watched says when it received something (touch); one thread cancels those silent for longer
// than the idle limit (ServerContext::TryCancel), so that their Read returns false at once.
//
// Lock: mutex_ guards the streams watched and stopping_; TryCancel is called under it, which
// gRPC allows from any thread.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>

#include <grpcpp/server_context.h>

namespace farm {

class StreamWatchdog {
 public:
  using Clock = std::chrono::steady_clock;

  explicit StreamWatchdog(std::chrono::milliseconds idle_limit);
  ~StreamWatchdog();
  StreamWatchdog(const StreamWatchdog&) = delete;
  StreamWatchdog& operator=(const StreamWatchdog&) = delete;

  // One stream watched while it lives.
  class Watch {
   public:
    Watch(Watch&& other) noexcept;
    Watch& operator=(Watch&&) = delete;
    Watch(const Watch&) = delete;
    ~Watch();
    void touch();  // something arrived
    bool timed_out() const;  // the watchdog cancelled the stream for its silence

   private:
    friend class StreamWatchdog;
    Watch(StreamWatchdog* owner, std::uint64_t id) : owner_(owner), id_(id) {}
    StreamWatchdog* owner_;
    std::uint64_t id_;
  };

  Watch watch(grpc::ServerContext& context);
  std::chrono::milliseconds idle_limit() const { return idle_limit_; }

 private:
  struct Stream {
    grpc::ServerContext* context;
    Clock::time_point last;
    bool cancelled = false;
  };
  void loop();

  const std::chrono::milliseconds idle_limit_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::uint64_t next_id_ = 0;
  std::map<std::uint64_t, Stream> streams_;
  std::thread thread_;  // last: started once the fields above exist
};

}  // namespace farm
