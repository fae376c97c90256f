#pragma once
// Running a student's program where it cannot hurt the grader (bubblewrap, Debian's `bwrap`):
// no network, the system read-only, only the folders it is given, in their own PID namespace,
// and limits on wall time, CPU time, memory, processes and the size of what it writes. Its
// output (stdout and stderr together) is kept up to a bound. Nothing it does can stop the
// grader: every way it ends is a SandboxResult.
//
// The grader runs as root (as in its container). The program does not: it runs as a user of its
// own, a uid no account has (2000000000 + the id of the calling thread, so two sandboxes running
// at once never share one), with no capabilities and no_new_privs. That is what makes the
// process limit hold (the kernel never applies RLIMIT_NPROC to root) and what keeps it from
// writing anything but its writable folders. Two consequences for the caller:
//  - what a read-only mount holds is read as that user: files must be readable by others
//    (o+r, folders o+rx), as what the grader writes with the usual umask 022 is;
//  - a writable folder is lent to that user for the run (chowned to it, everything in it) and
//    given back afterwards: everything in it then belongs to the folder's owner.
// The uid must be one this machine can switch to: in a container whose user namespace maps fewer
// uids (a rootless one) setpriv cannot, the run fails to start and sandbox_available() is
// false. When the program exits, whatever it left running in the background is killed with it.
// How each limit is enforced and read back is told in sandbox.cpp.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace farm {

struct SandboxLimits {
  double wall_seconds = 60.0;
  double cpu_seconds = 60.0;
  std::uint64_t memory_mib = 2048;          // address space of each process (RLIMIT_AS)
  int processes = 64;                       // processes and threads at once, inside the sandbox
  std::uint64_t file_size_mib = 256;        // the largest file it may write
  std::uint64_t work_folder_mib = 1024;     // all it may write in its writable folders together
                                            // (and the size of its /tmp)
  std::size_t output_bytes = 64 * 1024;     // of stdout+stderr kept (the rest is dropped)
};

struct SandboxMount {
  std::filesystem::path host;    // an existing file or folder
  std::filesystem::path inside;  // where the program sees it (absolute)
  bool writable = false;
};

struct SandboxRun {
  std::vector<std::string> argv;     // argv[0] looked up in PATH inside when it has no '/'
  std::filesystem::path workdir;     // inside; the current directory and HOME
  std::vector<SandboxMount> mounts;  // besides the read-only system (/usr, /bin, /lib*, /etc)
  std::vector<std::pair<std::string, std::string>> environment;  // beyond a minimal PATH, HOME, LANG
  SandboxLimits limits;
};

// bwrap reports a program killed by signal N as exit code 128 + N, as shells do, so an exit code
// above 128 is read as that signal.
enum class SandboxEnd {
  exited,           // exit_code says how
  signaled,         // killed by `signal` (a crash)
  wall_time,        // ran past limits.wall_seconds; killed
  cpu_time,         // used more than limits.cpu_seconds
  memory,           // crashed (SIGSEGV, SIGBUS, SIGABRT, SIGKILL) after using at least half of
                    // limits.memory_mib: what a refused allocation ends in; `signal` says which
  file_size,        // tried to write a file past limits.file_size_mib (`signal` is SIGXFSZ) or
                    // filled its writable folders past limits.work_folder_mib; killed
  processes,        // kept limits.processes running for a whole second (a fork bomb); killed
  failed_to_start,  // bwrap missing, a mount missing, the program not found: `detail` says
};

struct SandboxResult {
  SandboxEnd end = SandboxEnd::failed_to_start;
  int exit_code = -1;
  int signal = 0;
  std::string output;   // stdout+stderr: its first limits.output_bytes, then a note when cut
  std::string detail;   // for failed_to_start: what went wrong
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;              // user + system, all its processes together
  std::uint64_t peak_memory_bytes = 0;   // the largest resident size one of its processes reached
  bool ok() const { return end == SandboxEnd::exited && exit_code == 0; }
  // In words a student understands: "exited with code 2", "crashed (signal 11, SIGSEGV)",
  // "ran past its 60 s time limit", "ran out of memory (limit 2048 MiB)", ... A crash that is
  // not classed as memory names the memory limit too (an unchecked refused allocation crashes).
  std::string reason(const SandboxLimits& limits) const;
};

// True when bubblewrap is installed and a trivial program runs in it here (checked once).
bool sandbox_available();

SandboxResult run_sandboxed(const SandboxRun& run);

}  // namespace farm
