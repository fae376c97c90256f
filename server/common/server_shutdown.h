#pragma once
// The end of `farm worker` and `farm scheduler`: their gRPC server shut down within a bound.
//
// grpc::Server::Shutdown waits for every handler of the synchronous API to return, however long
// that takes: past its deadline it cancels the calls, but a handler busy in work that cannot be
// interrupted (a SubmitJob building a scene from a huge model) still holds the process until the
// work is done. Here the calls get `grace` to finish, are then cancelled (every handler that
// polls IsCancelled, RenderTile and WatchJob included, returns within milliseconds), and those
// still running `unwind` later are given up on: the process then ends without them.
#include <signal.h>

#include <chrono>
#include <string_view>

#include "server/common/farm_server.h"

namespace farm {

// Calls in flight get kShutdownGrace to finish after SIGINT/SIGTERM before they are cancelled (a
// cancelled render stops within milliseconds); one still running kShutdownUnwind later (preparing
// a scene or loading a huge model, which cannot be interrupted) is abandoned: a server is gone
// within 2 s.
inline constexpr auto kShutdownGrace = std::chrono::milliseconds(1400);
inline constexpr auto kShutdownUnwind = std::chrono::milliseconds(400);

// SIGINT and SIGTERM blocked from construction on, to be taken synchronously by wait(), so that no
// handler runs in signal context. Made before gRPC starts its threads (making credentials starts
// some), since threads inherit the mask and any thread left unblocked would take the signal.
class StopSignals {
 public:
  StopSignals();
  // Blocks until SIGINT or SIGTERM arrives; returns its name.
  std::string_view wait() const;

 private:
  sigset_t signals_;
};

// True when every handler returned in time: the server is shut down and may be destroyed. False
// when some still run: the server is left shutting down on a thread of its own and must not be
// destroyed, so the caller puts its own state in order and ends with exit_abandoning_calls().
bool shut_down_within(FarmServer& server, std::chrono::milliseconds grace = kShutdownGrace,
                      std::chrono::milliseconds unwind = kShutdownUnwind);

// Ends the process now with `code`, after flushing stdout and stderr, without running
// destructors: the handlers still running die with the process, in the middle of their work. Only
// for state that survives that, as a crash would leave it (files written to a temporary name and
// renamed into place, SQLite transactions). `farm render` ends this way too once its files are
// written: its embedded farm is left to the kernel rather than taken apart.
[[noreturn]] void exit_abandoning_calls(int code);

}  // namespace farm
