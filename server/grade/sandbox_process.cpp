#include "server/grade/sandbox_process.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <initializer_list>
#include <stdexcept>

namespace farm {
namespace {

// Everything the child needs, made before it starts: between clone and execve it may only make
// async-signal-safe calls (the grader has other threads; one may hold the malloc lock).
struct ChildPlan {
  char* const* argv = nullptr;
  char* const* envp = nullptr;
  int output_fd = -1;    // the pipe's write end
  int error_fd = -1;     // where the child says why it failed, if it does (close-on-exec)
  int dev_null_fd = -1;
  SandboxRlimits rlimits;
};

struct ChildError {
  int error = 0;
  char step[40] = {};
};

[[noreturn]] void child_fails(int error_fd, const char* step) {
  ChildError message;
  message.error = errno;
  std::strncpy(message.step, step, sizeof message.step - 1);
  [[maybe_unused]] const ssize_t ignored = write(error_fd, &message, sizeof message);
  _exit(127);
}

bool set_limit(int resource, rlim_t soft, rlim_t hard) {
  const rlimit limit{soft, hard};
  return setrlimit(resource, &limit) == 0;
}

// pid 1 of the new PID namespace, until it executes bwrap.
int child_main(void* arg) {
  const ChildPlan& plan = *static_cast<const ChildPlan*>(arg);
  // Nothing of the grader's signal set-up (an ignored SIGPIPE, a blocked SIGTERM) carries over.
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  for (int signal = 1; signal < NSIG; ++signal) sigaction(signal, &default_action, nullptr);

  int error_fd = plan.error_fd;
  if (setsid() < 0) child_fails(error_fd, "setsid");
  if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0) child_fails(error_fd, "prctl(PR_SET_PDEATHSIG)");
  const int pid_namespace = open("/proc/self/ns/pid", O_RDONLY | O_CLOEXEC);
  if (pid_namespace < 0) child_fails(error_fd, "open /proc/self/ns/pid");

  // Descriptors 0-3 as bwrap wants them, the error pipe at 4, and nothing else: first out of the
  // way (above 9), then into place.
  const int high_null = fcntl(plan.dev_null_fd, F_DUPFD_CLOEXEC, 10);
  const int high_output = fcntl(plan.output_fd, F_DUPFD_CLOEXEC, 10);
  const int high_namespace = fcntl(pid_namespace, F_DUPFD_CLOEXEC, 10);
  const int high_error = fcntl(error_fd, F_DUPFD_CLOEXEC, 10);
  if (high_null < 0 || high_output < 0 || high_namespace < 0 || high_error < 0) child_fails(error_fd, "fcntl");
  if (dup3(high_error, 4, O_CLOEXEC) < 0) child_fails(error_fd, "dup3");
  error_fd = 4;
  if (dup2(high_null, STDIN_FILENO) < 0 || dup2(high_output, STDOUT_FILENO) < 0 ||
      dup2(high_output, STDERR_FILENO) < 0 || dup2(high_namespace, SandboxProcess::kPidNamespaceFd) < 0) {
    child_fails(error_fd, "dup2");
  }
  if (close_range(5, ~0U, 0) != 0) {
    rlimit files{};
    getrlimit(RLIMIT_NOFILE, &files);
    for (rlim_t fd = 5; fd < files.rlim_cur && fd < (1U << 20); ++fd) close(static_cast<int>(fd));
  }

  const SandboxRlimits& limits = plan.rlimits;
  if (!set_limit(RLIMIT_AS, limits.address_space_bytes, limits.address_space_bytes) ||
      !set_limit(RLIMIT_CPU, limits.cpu_seconds, limits.cpu_seconds + 1) ||
      !set_limit(RLIMIT_FSIZE, limits.file_size_bytes, limits.file_size_bytes) ||
      !set_limit(RLIMIT_NPROC, limits.processes, limits.processes) || !set_limit(RLIMIT_CORE, 0, 0)) {
    child_fails(error_fd, "setrlimit");
  }
  execve(plan.argv[0], plan.argv, plan.envp);
  child_fails(error_fd, "execve");
}

double seconds(const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; }

void close_all(std::initializer_list<int> fds) {
  for (int fd : fds) {
    if (fd >= 0) close(fd);
  }
}

}  // namespace

SandboxProcess::SandboxProcess(const std::vector<std::string>& argv, const SandboxRlimits& rlimits) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  char* no_environment[] = {nullptr};  // bwrap needs none; the program's own is in its arguments

  int output[2] = {-1, -1}, error[2] = {-1, -1};
  const int dev_null = open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (dev_null < 0 || pipe2(output, O_CLOEXEC) != 0 || pipe2(error, O_CLOEXEC) != 0) {
    const std::string why = std::strerror(errno);
    close_all({dev_null, output[0], output[1], error[0]});
    throw std::runtime_error("cannot make the sandbox's pipes: " + why);
  }
  ChildPlan plan{args.data(), no_environment, output[1], error[1], dev_null, rlimits};

  // clone() with a stack of its own rather than fork(): fork has no flag for a new PID namespace.
  std::vector<char> stack(256 * 1024);
  pid_ = clone(child_main, stack.data() + stack.size(), CLONE_NEWPID | SIGCHLD, &plan);
  const int clone_error = errno;
  close_all({output[1], error[1], dev_null});
  output_fd_ = output[0];
  if (pid_ < 0) {
    close_all({output_fd_, error[0]});
    throw std::runtime_error(std::string("cannot make a PID namespace for the sandbox (clone: ") +
                             std::strerror(clone_error) + "; the grader must run as root)");
  }
  ChildError message;
  ssize_t got;
  do {
    got = read(error[0], &message, sizeof message);
  } while (got < 0 && errno == EINTR);
  close(error[0]);
  if (got > 0) {  // the child failed before bwrap ran (got == 0: execve closed the pipe)
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
    close(output_fd_);
    output_fd_ = -1;
    throw std::runtime_error("cannot start " + argv.front() + ": " + message.step + ": " +
                             std::strerror(message.error));
  }
}

SandboxProcess::~SandboxProcess() {
  if (!reaped_ && pid_ > 0) {
    ::kill(pid_, SIGKILL);
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  if (output_fd_ >= 0) close(output_fd_);
}

std::optional<SandboxExit> SandboxProcess::poll_exit() {
  if (reaped_) return std::nullopt;
  int status = 0;
  rusage usage{};
  const pid_t got = wait4(pid_, &status, WNOHANG, &usage);
  if (got == pid_) {
    reaped_ = true;
    // ru_maxrss is in KiB on Linux, and for a waited-for child already the largest of its own
    // and of every descendant it waited for.
    return SandboxExit{status, seconds(usage.ru_utime) + seconds(usage.ru_stime),
                       static_cast<std::uint64_t>(usage.ru_maxrss) * 1024};
  }
  if (got < 0 && errno == ECHILD) {  // reaped by someone else (a grader that ignores SIGCHLD)
    reaped_ = true;
    return SandboxExit{W_EXITCODE(255, 0), 0.0, 0};
  }
  return std::nullopt;
}

void SandboxProcess::kill() {
  // bwrap is pid 1 of the namespace: when it dies the kernel kills everything else in it.
  if (!reaped_) ::kill(pid_, SIGKILL);
}

}  // namespace farm
