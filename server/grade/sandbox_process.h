#pragma once
// The process a sandbox lives in (sandbox.h): bwrap, started as pid 1 of a PID namespace of its
// own. Killing it makes the kernel kill every process in the namespace, however many the program
// forked; and since every level reaps the one below (bwrap waits for the program), waiting for
// it returns the CPU time and the peak memory of them all. Its stdout and stderr go into one
// pipe, its stdin is /dev/null, no other descriptor of the grader reaches it, and the program's
// limits are rlimits set before bwrap starts, which it and the program inherit.
#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace farm {

struct SandboxRlimits {
  std::uint64_t address_space_bytes = 0;  // RLIMIT_AS
  std::uint64_t cpu_seconds = 0;          // RLIMIT_CPU: SIGXCPU then, a second later, SIGKILL
  std::uint64_t file_size_bytes = 0;      // RLIMIT_FSIZE: SIGXFSZ
  std::uint64_t processes = 0;            // RLIMIT_NPROC, of the user the program runs as
};

struct SandboxExit {
  int status = 0;  // as waitpid says, of bwrap
  double cpu_seconds = 0.0;
  std::uint64_t peak_memory_bytes = 0;
};

class SandboxProcess {
 public:
  // The descriptor bwrap finds its PID namespace at (for --pidns).
  static constexpr int kPidNamespaceFd = 3;

  // Starts argv (argv[0] an absolute path); throws std::runtime_error saying why it could not.
  SandboxProcess(const std::vector<std::string>& argv, const SandboxRlimits& rlimits);
  ~SandboxProcess();  // kills and reaps it if it still runs
  SandboxProcess(const SandboxProcess&) = delete;
  SandboxProcess& operator=(const SandboxProcess&) = delete;

  int output_fd() const { return output_fd_; }
  // How it ended, once it has (never blocks).
  std::optional<SandboxExit> poll_exit();
  void kill();

 private:
  pid_t pid_ = -1;
  int output_fd_ = -1;
  bool reaped_ = false;
};

}  // namespace farm
