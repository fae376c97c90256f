#pragma once
// Running a student's program where it cannot hurt the grader (bubblewrap, Debian's `bwrap`):
// no network, the system read-only, only the folders it is given, in their own PID namespace,
// and limits on wall time, CPU time, memory, processes and the size of what it writes. Its
// output (stdout and stderr together) is kept up to a bound. Nothing it does can stop the
// grader: every way it ends is a SandboxResult.
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
  std::uint64_t memory_mib = 2048;          // address space of each process
  int processes = 64;                       // at once, inside the sandbox
  std::uint64_t file_size_mib = 256;        // the largest file it may write
  std::uint64_t work_folder_mib = 1024;     // all it may write in its work folder together
  std::size_t output_bytes = 64 * 1024;     // of stdout+stderr kept (the rest is dropped)
};

struct SandboxMount {
  std::filesystem::path host;    // an existing file or folder
  std::filesystem::path inside;  // where the program sees it (absolute)
  bool writable = false;
};

struct SandboxRun {
  std::vector<std::string> argv;     // argv[0] looked up in PATH inside when it has no '/'
  std::filesystem::path workdir;     // inside; the current directory
  std::vector<SandboxMount> mounts;  // besides the read-only system (/usr, /bin, /lib*, /etc)
  std::vector<std::pair<std::string, std::string>> environment;  // beyond a minimal PATH, HOME, LANG
  SandboxLimits limits;
};

enum class SandboxEnd {
  exited,           // exit_code says how
  signaled,         // killed by `signal` (a crash)
  wall_time,        // ran past limits.wall_seconds; killed
  cpu_time,         // used more than limits.cpu_seconds
  memory,           // an allocation was refused or it was killed for memory
  file_size,        // tried to write a file past limits.file_size_mib (or filled its work folder)
  failed_to_start,  // bwrap missing, a mount missing, the program not found: `detail` says
};

struct SandboxResult {
  SandboxEnd end = SandboxEnd::failed_to_start;
  int exit_code = -1;
  int signal = 0;
  std::string output;   // stdout+stderr, at most limits.output_bytes (a note says when cut)
  std::string detail;   // for failed_to_start: what went wrong
  double wall_seconds = 0.0;
  bool ok() const { return end == SandboxEnd::exited && exit_code == 0; }
  // In words a student understands: "exited with code 2", "crashed (signal 11, SIGSEGV)",
  // "ran past its 60 s time limit", "ran out of memory (limit 2048 MiB)", ...
  std::string reason(const SandboxLimits& limits) const;
};

// True when bubblewrap is installed and can make namespaces here (checked once).
bool sandbox_available();

SandboxResult run_sandboxed(const SandboxRun& run);

}  // namespace farm
