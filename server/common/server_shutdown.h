#pragma once
// The end of `farm worker` and `farm scheduler`: their gRPC server shut down within a bound.
//
// grpc::Server::Shutdown waits for every handler of the synchronous API to return, however long
// that takes: past its deadline it cancels the calls, but a handler busy in work that cannot be
// interrupted (a SubmitJob building a scene from a huge model) still holds the process until the
// work is done. Here the calls get `grace` to finish, are then cancelled (every handler that
// polls IsCancelled, RenderTile and WatchJob included, returns within milliseconds), and those
// still running `unwind` later are given up on: the process then ends without them.
#include <chrono>

#include "server/common/farm_server.h"

namespace farm {

// True when every handler returned in time: the server is shut down and may be destroyed. False
// when some still run: the server is left shutting down on a thread of its own and must not be
// destroyed, so the caller puts its own state in order and ends with exit_abandoning_calls().
bool shut_down_within(FarmServer& server, std::chrono::milliseconds grace,
                      std::chrono::milliseconds unwind);

// Ends the process now with `code`, after flushing stdout and stderr, without running
// destructors: the handlers still running die with the process, in the middle of their work. Only
// for state that survives that, as a crash would leave it (files written to a temporary name and
// renamed into place, SQLite transactions).
[[noreturn]] void exit_abandoning_calls(int code);

}  // namespace farm
