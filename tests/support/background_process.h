#pragma once
// Processes beside a test: farm::ChildProcess (server/common/child_process.h) and the `farm worker`
// binary under test on a free port.
#include <cstddef>
#include <string>
#include <vector>

#include "server/common/child_process.h"

namespace farm::test {

using BackgroundProcess = farm::ChildProcess;

// The `farm worker` binary under test on a free port; waits for its "listening" line.
class WorkerProcess {
 public:
  explicit WorkerProcess(const std::vector<std::string>& extra_args = {});
  const std::string& address() const { return address_; }  // empty if it did not start
  BackgroundProcess& process() { return process_; }

 private:
  BackgroundProcess process_;
  std::string address_;
};

// How many processes have `pid` as their parent now (from /proc/*/stat).
std::size_t children_of(int pid);

// What /proc/PID/status says a process costs now.
struct ProcStatus {
  long threads = 0, vm_size_kb = 0, vm_rss_kb = 0;
};
ProcStatus proc_status(int pid);

}  // namespace farm::test
