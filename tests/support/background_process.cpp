#include "tests/support/background_process.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace farm::test {

WorkerProcess::WorkerProcess(const std::vector<std::string>& extra_args)
    : process_([&] {
        std::vector<std::string> argv{FARM_BINARY, "worker", "--listen", "127.0.0.1:0"};
        argv.insert(argv.end(), extra_args.begin(), extra_args.end());
        return argv;
      }()),
      address_(wait_for_listening(process_, "worker", std::chrono::seconds(30))) {}

std::size_t children_of(int pid) {
  std::size_t children = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    std::ifstream in(entry.path() / "stat");
    std::string stat;
    if (!std::getline(in, stat)) continue;
    // pid (comm) state ppid ...: the command name may hold spaces and parentheses.
    const std::size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(stat.substr(close + 1));
    std::string state;
    int ppid = 0;
    if (fields >> state >> ppid && ppid == pid) ++children;
  }
  return children;
}

ProcStatus proc_status(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  ProcStatus s;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    long value = 0;
    fields >> key >> value;
    if (key == "Threads:") s.threads = value;
    if (key == "VmSize:") s.vm_size_kb = value;
    if (key == "VmRSS:") s.vm_rss_kb = value;
  }
  return s;
}

}  // namespace farm::test
