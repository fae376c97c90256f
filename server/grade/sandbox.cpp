// run_sandboxed: how each limit of SandboxLimits is enforced, and how the way a run ended is read.
//
// The sandbox is bwrap (sandbox_command.cpp) started as pid 1 of a PID namespace of its own
// (sandbox_process.cpp); setpriv drops the program to a uid of its own before executing it.
//  - wall time: the grader watches the clock and kills bwrap, which takes every process in the
//    namespace with it (the kernel kills a namespace whose pid 1 dies).
//  - CPU time: RLIMIT_CPU, per process: SIGXCPU, and SIGKILL a second later if it was caught.
//  - memory: RLIMIT_AS, per process: an allocation past it fails. The program sees that (NULL,
//    std::bad_alloc, MemoryError) and may report it and exit, which is an honest exit; when it
//    crashes instead, sandbox_verdict.cpp reads the crash as memory if the program had come near
//    the limit (the peak resident size of all processes, from wait4). No cgroup: containers
//    seldom let one be made, and address space needs none.
//  - processes: RLIMIT_NPROC, which counts every process and thread of a (real) uid on the
//    machine, and which the kernel never applies to root. Hence the program's own uid, unique to
//    the calling thread while it runs: a fork bomb's forks fail at the limit and nothing else on
//    the machine is touched. A bomb then keeps its processes busy at the limit; the grader counts
//    them (sandbox_watch.cpp) and stops a sandbox that has sat at the limit for a second.
//  - file size: RLIMIT_FSIZE: SIGXFSZ on a write past it. The writable folders together: the
//    grader measures them (sandbox_watch.cpp, every 200 ms, less often when that takes long)
//    and kills the sandbox past work_folder_mib. A size-limited tmpfs would enforce it exactly,
//    but what the program writes must outlive it in the folder the grader gave. /tmp is such a
//    tmpfs (of work_folder_mib).
//  - output: one pipe for stdout and stderr, always drained; the first output_bytes are kept.
#include "server/grade/sandbox.h"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <optional>
#include <thread>

#include "server/grade/folder_loan.h"
#include "server/grade/sandbox_command.h"
#include "server/grade/sandbox_process.h"
#include "server/grade/sandbox_verdict.h"
#include "server/grade/sandbox_watch.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

// The program's uid is this plus the calling thread's id: no account has one this high, and no
// two threads running at once share an id (pid_max is at most 2^22). Graders in two containers
// of one machine (two PID namespaces) could meet on one; they would share a process limit, and
// nothing else: neither sees the other's processes or folders.
constexpr unsigned kFirstSandboxUid = 2'000'000'000;

// The first `limit` bytes of the output; the rest only counted.
class KeptOutput {
 public:
  explicit KeptOutput(std::size_t limit) : limit_(limit) {}
  void add(const char* data, std::size_t size) {
    const std::size_t kept = std::min(size, limit_ - std::min(limit_, text_.size()));
    text_.append(data, kept);
    cut_ += size - kept;
  }
  std::string take() {
    if (cut_ > 0) text_ += "\n[... " + std::to_string(cut_) + " bytes cut]\n";
    return std::move(text_);
  }

 private:
  std::size_t limit_;
  std::size_t cut_ = 0;
  std::string text_;
};

SandboxRlimits rlimits_of(const SandboxLimits& limits) {
  return {limits.memory_mib << 20, static_cast<std::uint64_t>(std::max(1.0, std::ceil(limits.cpu_seconds))),
          limits.file_size_mib << 20, static_cast<std::uint64_t>(std::max(1, limits.processes))};
}

struct Watched {
  SandboxExit exit;
  SandboxStop stop = SandboxStop::none;
};

// Drains the output and watches the limits the kernel does not enforce, until bwrap has exited
// (or been killed) and the output has ended.
Watched watch(SandboxProcess& process, const SandboxRun& run, uid_t uid, const std::vector<fs::path>& writable,
              KeptOutput& output, Clock::time_point start) {
  const auto wall_limit = std::chrono::duration<double>(run.limits.wall_seconds);
  Watched watched;
  std::optional<SandboxExit> exit;
  Clock::time_point exited_at, next_process_count = start, next_folder_scan = start;
  Clock::time_point at_process_limit_since = Clock::time_point::max();  // max: not at the limit
  bool output_open = true;
  char buffer[65536];
  while (true) {
    if (output_open) {
      pollfd ready{process.output_fd(), POLLIN, 0};
      if (poll(&ready, 1, 50) > 0) {
        const ssize_t got = read(process.output_fd(), buffer, sizeof buffer);
        if (got > 0) output.add(buffer, static_cast<std::size_t>(got));
        if (got == 0 || (got < 0 && errno != EINTR && errno != EAGAIN)) output_open = false;
      }
    } else if (!exit) {
      std::this_thread::sleep_for(50ms);
    }
    const Clock::time_point now = Clock::now();
    if (!exit && (exit = process.poll_exit())) exited_at = now;
    if (exit) {
      // With bwrap (pid 1) gone nothing in the sandbox is left to hold the pipe open.
      if (!output_open || now - exited_at > 2s) break;
      continue;
    }
    if (watched.stop != SandboxStop::none) continue;  // killed; waiting to reap it
    if (now - start >= wall_limit) {
      watched.stop = SandboxStop::wall_time;
    } else if (now >= next_process_count) {
      next_process_count = now + 100ms;
      if (count_processes_of(uid) < run.limits.processes) {
        at_process_limit_since = Clock::time_point::max();
      } else if (at_process_limit_since == Clock::time_point::max()) {
        at_process_limit_since = now;
      } else if (now - at_process_limit_since >= 1s) {
        watched.stop = SandboxStop::processes;
      }
    }
    if (watched.stop == SandboxStop::none && !writable.empty() && now >= next_folder_scan) {
      const std::uint64_t used = disk_usage(writable);
      const Clock::duration took = Clock::now() - now;
      next_folder_scan = Clock::now() + std::max<Clock::duration>(200ms, 10 * took);
      // The folders' own blocks and a large file's extent blocks are counted too: a program that
      // wrote no more than the limit in data (one file stopped at RLIMIT_FSIZE, whose own
      // SIGXFSZ is then the verdict) must not be over it by a block or two.
      const std::uint64_t limit = run.limits.work_folder_mib << 20;
      if (used > limit + limit / 64 + (std::uint64_t{1} << 20)) watched.stop = SandboxStop::work_folder;
    }
    if (watched.stop != SandboxStop::none) process.kill();
  }
  watched.exit = *exit;
  return watched;
}

}  // namespace

SandboxResult run_sandboxed(const SandboxRun& run) {
  const Clock::time_point start = Clock::now();
  SandboxResult result;
  const auto failed = [&](std::string detail) {
    result.end = SandboxEnd::failed_to_start;
    result.detail = std::move(detail);
    result.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    return result;
  };
  const SandboxTools tools = find_sandbox_tools();
  if (tools.bwrap.empty()) return failed("bubblewrap is not installed (no bwrap; Debian package bubblewrap)");
  if (tools.setpriv.empty()) return failed("setpriv is not installed in /usr/bin (Debian package util-linux)");
  if (std::string why = check_sandbox_run(run); !why.empty()) return failed(why);

  const auto uid = static_cast<uid_t>(kFirstSandboxUid + static_cast<unsigned>(gettid()));
  std::vector<fs::path> writable;
  for (const SandboxMount& mount : run.mounts) {
    if (mount.writable) writable.push_back(mount.host);
  }
  KeptOutput output(run.limits.output_bytes);
  try {
    const FolderLoan loan(writable, uid, uid);
    Watched watched;
    {
      SandboxProcess process(sandbox_command(run, tools, uid, SandboxProcess::kPidNamespaceFd), rlimits_of(run.limits));
      watched = watch(process, run, uid, writable, output, start);
    }
    result.output = output.take();
    judge_sandbox_exit(result, watched.stop, watched.exit, run.limits);
  } catch (const std::exception& e) {
    return failed(e.what());
  }
  result.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

bool sandbox_available() {
  static const bool available = [] {
    SandboxRun run;
    run.argv = {"true"};
    run.workdir = "/tmp";
    run.limits.wall_seconds = 20.0;
    return run_sandboxed(run).ok();
  }();
  return available;
}

}  // namespace farm
