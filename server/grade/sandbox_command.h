#pragma once
// The bubblewrap command line of one sandboxed run (sandbox.h): its namespaces, the read-only
// system, the run's own mounts, a fresh /tmp, a clean environment, and setpriv (util-linux) as
// the command bwrap starts, which drops to the run's user before it executes the program.
#include <filesystem>
#include <string>
#include <vector>

#include "server/grade/sandbox.h"

namespace farm {

struct SandboxTools {
  std::filesystem::path bwrap;    // empty when not installed
  std::filesystem::path setpriv;  // under /usr, so the sandbox sees it too; empty when missing
};

SandboxTools find_sandbox_tools();

// Why `run` cannot be run (a mount or path that cannot work), or empty when it looks runnable.
std::string check_sandbox_run(const SandboxRun& run);

// `pid_namespace_fd`: the descriptor bwrap gets of the PID namespace it runs in as pid 1, where
// it starts the program (--pidns): bwrap's own --unshare-pid would put the program under an
// init bwrap never waits for, and its CPU time and peak memory would be lost.
std::vector<std::string> sandbox_command(const SandboxRun& run, const SandboxTools& tools, unsigned uid,
                                         int pid_namespace_fd);

}  // namespace farm
