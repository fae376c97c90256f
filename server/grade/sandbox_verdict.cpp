#include "server/grade/sandbox_verdict.h"

#include <fmt/format.h>
#include <signal.h>
#include <string.h>
#include <sys/wait.h>

#include <optional>
#include <string_view>

namespace farm {
namespace {

std::string first_line(std::string_view text) { return std::string(text.substr(0, text.find('\n'))); }

// The program never ran when bwrap could not set the sandbox up ("bwrap: Can't find source path
// ...", exit code 1) or setpriv could not execute it ("setpriv: failed to execute prog: No such
// file or directory", 127; 126 when it is not executable): each prints one line and nothing
// else has printed before it. That a program could print the same and exit the same way is no
// risk: it would only hide its own result.
std::optional<std::string> setup_failure(int exit_code, const std::string& output) {
  if (exit_code == 1 && output.starts_with("bwrap: ")) return first_line(output);
  if ((exit_code == 1 || exit_code == 126 || exit_code == 127) && output.starts_with("setpriv: ")) {
    return first_line(output);
  }
  return std::nullopt;
}

// What a refused allocation ends in when the program does not check for it: a null pointer
// written to (SIGSEGV, SIGBUS), std::bad_alloc uncaught or abort() (SIGABRT); SIGKILL is the
// kernel's out-of-memory killer.
bool memory_like(int signal) { return signal == SIGSEGV || signal == SIGBUS || signal == SIGABRT || signal == SIGKILL; }

SandboxEnd end_by_signal(int signal, const SandboxExit& exit, const SandboxLimits& limits) {
  if (signal == SIGXCPU) return SandboxEnd::cpu_time;  // RLIMIT_CPU's soft limit
  if (signal == SIGXFSZ) return SandboxEnd::file_size;  // RLIMIT_FSIZE
  if (signal == SIGKILL && exit.cpu_seconds >= limits.cpu_seconds) return SandboxEnd::cpu_time;  // its hard limit
  // RLIMIT_AS leaves no trace of a refused allocation, so a crash is read as memory only when
  // the program had come near its limit: at least half of it resident (what a program that
  // allocates until refused reaches; one huge allocation refused at once stays a crash).
  if (memory_like(signal) && exit.peak_memory_bytes * 2 >= (limits.memory_mib << 20)) return SandboxEnd::memory;
  return SandboxEnd::signaled;
}

std::string signal_name(int signal) {
  const char* abbreviation = sigabbrev_np(signal);
  return abbreviation ? std::string("SIG") + abbreviation : "unknown signal";
}

}  // namespace

void judge_sandbox_exit(SandboxResult& result, SandboxStop stop, const SandboxExit& exit, const SandboxLimits& limits) {
  result.cpu_seconds = exit.cpu_seconds;
  result.peak_memory_bytes = exit.peak_memory_bytes;
  switch (stop) {
    case SandboxStop::wall_time: result.end = SandboxEnd::wall_time; return;
    case SandboxStop::processes: result.end = SandboxEnd::processes; return;
    case SandboxStop::work_folder: result.end = SandboxEnd::file_size; return;
    case SandboxStop::none: break;
  }
  int signal = 0;
  if (WIFSIGNALED(exit.status)) {
    signal = WTERMSIG(exit.status);  // bwrap itself, which only the kernel kills (for memory)
  } else {
    const int code = WEXITSTATUS(exit.status);
    if (std::optional<std::string> why = setup_failure(code, result.output)) {
      result.end = SandboxEnd::failed_to_start;
      result.detail = std::move(*why);
      return;
    }
    if (code <= 128 || code >= 128 + NSIG) {
      result.end = SandboxEnd::exited;
      result.exit_code = code;
      return;
    }
    signal = code - 128;  // bwrap's way of saying the program was killed by a signal
  }
  result.signal = signal;
  result.end = end_by_signal(signal, exit, limits);
}

std::string SandboxResult::reason(const SandboxLimits& limits) const {
  const auto mib = [](std::uint64_t bytes) { return (bytes + (1 << 19)) >> 20; };
  switch (end) {
    case SandboxEnd::exited: return fmt::format("exited with code {}", exit_code);
    case SandboxEnd::signaled: {
      std::string text = fmt::format("crashed (signal {}, {})", signal, signal_name(signal));
      if (memory_like(signal)) {
        text += fmt::format("; note that an allocation past its memory limit of {} MiB fails", limits.memory_mib);
      }
      return text;
    }
    case SandboxEnd::wall_time: return fmt::format("ran past its {:g} s time limit", limits.wall_seconds);
    case SandboxEnd::cpu_time: return fmt::format("used more than its {:g} s of CPU time", limits.cpu_seconds);
    case SandboxEnd::memory:
      return fmt::format("ran out of memory (limit {} MiB): it crashed ({}) having used {} MiB", limits.memory_mib,
                         signal_name(signal), mib(peak_memory_bytes));
    case SandboxEnd::file_size:
      if (signal == SIGXFSZ) return fmt::format("tried to write a file larger than {} MiB", limits.file_size_mib);
      return fmt::format("wrote more than the {} MiB its folders may hold", limits.work_folder_mib);
    case SandboxEnd::processes:
      return fmt::format("started too many processes (limit {}): killed after a second at the limit", limits.processes);
    case SandboxEnd::failed_to_start: return "could not be started: " + detail;
  }
  return "ended in an unknown way";
}

}  // namespace farm
