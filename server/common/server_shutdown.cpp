#include "server/common/server_shutdown.h"

#include <cstdio>
#include <cstdlib>
#include <future>
#include <memory>
#include <thread>

namespace farm {

StopSignals::StopSignals() {
  sigemptyset(&signals_);
  sigaddset(&signals_, SIGINT);
  sigaddset(&signals_, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals_, nullptr);
}

std::string_view StopSignals::wait() const {
  int number = 0;
  sigwait(&signals_, &number);
  return number == SIGINT ? "SIGINT" : "SIGTERM";
}

bool shut_down_within(FarmServer& server, std::chrono::milliseconds grace,
                      std::chrono::milliseconds unwind) {
  const auto deadline = std::chrono::system_clock::now() + grace;
  auto done = std::make_shared<std::promise<void>>();
  std::future<void> finished = done->get_future();
  // Shutdown blocks until the last handler returns, so it waits on a thread of its own while this
  // one keeps the time.
  std::thread shutting_down([&server, deadline, done] {
    server.Shutdown(deadline);
    server.Wait();
    done->set_value();
  });
  if (finished.wait_for(grace + unwind) == std::future_status::ready) {
    shutting_down.join();
    return true;
  }
  shutting_down.detach();  // it dies with the process (exit_abandoning_calls)
  return false;
}

void exit_abandoning_calls(int code) {
  std::fflush(nullptr);
  std::_Exit(code);
}

}  // namespace farm
