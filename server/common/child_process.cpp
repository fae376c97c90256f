#include "server/common/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string_view>
#include <thread>

extern char** environ;

namespace farm {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe failed");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  out_fd_ = fds[0];
  if (rc != 0) {
    close(out_fd_);
    throw std::runtime_error("cannot start " + argv.front());
  }
  // By syscall: glibc 2.36's <sys/pidfd.h> declares pidfd_open without C linkage for C++.
  pid_fd_ = static_cast<int>(syscall(SYS_pidfd_open, pid_, 0));
  reader_ = std::thread([this] { read_output(); });
}

ChildProcess::~ChildProcess() {
  if (!exit_code_) {
    kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  // The reader polls, so it stops even if a grandchild still holds the pipe open.
  stop_reading_ = true;
  reader_.join();
  close(out_fd_);
  if (pid_fd_ >= 0) close(pid_fd_);
}

void ChildProcess::read_output() {
  std::array<char, 4096> buffer;
  while (!stop_reading_) {
    pollfd p{out_fd_, POLLIN, 0};
    if (poll(&p, 1, 50) <= 0) continue;
    const ssize_t n = read(out_fd_, buffer.data(), buffer.size());
    std::lock_guard lock(mutex_);
    if (n <= 0) {
      eof_ = true;
      output_changed_.notify_all();
      return;
    }
    output_.append(buffer.data(), static_cast<std::size_t>(n));
    if (output_.size() > kMaxOutputBytes) {
      // Keep the tail, from a line start.
      const std::size_t cut = output_.find('\n', output_.size() - kMaxOutputBytes);
      output_.erase(0, cut == std::string::npos ? output_.size() - kMaxOutputBytes : cut + 1);
    }
    output_changed_.notify_all();
  }
}

std::string ChildProcess::output() const {
  std::lock_guard lock(mutex_);
  return output_;
}

std::optional<std::string> ChildProcess::wait_for_line(const std::string& needle,
                                                            std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  std::unique_lock lock(mutex_);
  for (;;) {
    for (std::size_t begin = 0, nl; (nl = output_.find('\n', begin)) != std::string::npos;
         begin = nl + 1) {
      const std::string_view line = std::string_view(output_).substr(begin, nl - begin);
      if (line.find(needle) != std::string_view::npos) return std::string(line);
    }
    if (eof_) return std::nullopt;
    if (output_changed_.wait_until(lock, end) == std::cv_status::timeout) {
      if (Clock::now() >= end) return std::nullopt;
    }
  }
}

std::string ChildProcess::output_to_end(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  output_changed_.wait_for(lock, timeout, [this] { return eof_; });
  return output_;
}

void ChildProcess::send_signal(int signal) {
  if (!exit_code_) kill(pid_, signal);
}

std::optional<int> ChildProcess::wait_exit(std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (!exit_code_) {
    int status = 0;
    rusage usage{};
    if (wait4(pid_, &status, WNOHANG, &usage) == pid_) {
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      const auto seconds = [](const timeval& t) {
        return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
      };
      cpu_seconds_ = seconds(usage.ru_utime) + seconds(usage.ru_stime);
      kernel_seconds_ = seconds(usage.ru_stime);
      peak_memory_bytes_ = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // Linux: KiB
      break;
    }
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(end - Clock::now());
    if (left.count() <= 0) return std::nullopt;
    if (pid_fd_ >= 0) {
      pollfd p{pid_fd_, POLLIN, 0};
      poll(&p, 1, static_cast<int>(std::min<std::int64_t>(left.count(), 1000)));
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  return exit_code_;
}

std::string wait_for_listening(ChildProcess& process, const std::string& what, std::chrono::milliseconds timeout) {
  const std::string prefix = what + " listening on ";
  if (auto line = process.wait_for_line(prefix, timeout)) return line->substr(line->find(prefix) + prefix.size());
  return {};
}

}  // namespace farm
