#include "tests/support/background_process.h"

#include <chrono>

namespace farm::test {

WorkerProcess::WorkerProcess(const std::vector<std::string>& extra_args)
    : process_([&] {
        std::vector<std::string> argv{FARM_BINARY, "worker", "--listen", "127.0.0.1:0"};
        argv.insert(argv.end(), extra_args.begin(), extra_args.end());
        return argv;
      }()),
      address_(wait_for_listening(process_, "worker", std::chrono::seconds(30))) {}

}  // namespace farm::test
