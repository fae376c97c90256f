#pragma once
// A child process (a `farm worker` or `farm scheduler` started by a test or by `farm bench farm`),
// its stdout and stderr read through a pipe by a thread of its own, all the time: a chatty child
// (a scheduler logs every job) must never block on a full pipe while nobody waits for a line.
// Every wait is bounded by a timeout; the destructor kills and reaps a child still running.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace farm {

class ChildProcess {
 public:
  explicit ChildProcess(const std::vector<std::string>& argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Reads output until a line containing `needle` has arrived and returns that line; nullopt when
  // the timeout passes or the process closes its output first.
  std::optional<std::string> wait_for_line(const std::string& needle,
                                           std::chrono::milliseconds timeout);
  // Everything read so far (the last kMaxOutputBytes of it).
  std::string output() const;
  // Everything, once the child has closed its output (it has exited, and its last words are read
  // only after that); what was read by then if `timeout` passes first.
  std::string output_to_end(std::chrono::milliseconds timeout);

  void send_signal(int signal);
  pid_t pid() const { return pid_; }  // for /proc/PID: what the child costs in threads and memory
  // The exit code (128 + signal for a killed child), or nullopt if it is still running after
  // `timeout`. Output keeps being drained meanwhile. Returns the moment the child ends (it waits
  // on a pidfd; polling every 5 ms, as it did, put up to 5 ms on `farm bench render`'s times).
  std::optional<int> wait_exit(std::chrono::milliseconds timeout);
  // The CPU time (user and system, all its threads) of a child wait_exit has seen end; nullopt
  // before. `farm bench render` shows from it how many cores a command kept busy.
  std::optional<double> cpu_seconds() const { return cpu_seconds_; }
  // Of that, the kernel's part (system time: page faults and the zeroing of fresh memory among
  // it), and the child's peak resident memory; nullopt before it has ended.
  std::optional<double> kernel_seconds() const { return kernel_seconds_; }
  std::optional<std::uint64_t> peak_memory_bytes() const { return peak_memory_bytes_; }

 private:
  static constexpr std::size_t kMaxOutputBytes = std::size_t{8} << 20;
  void read_output();  // the reader thread

  pid_t pid_ = -1;
  int pid_fd_ = -1;  // readable once the child has ended; -1 where the kernel has no pidfd_open
  int out_fd_ = -1;
  std::optional<int> exit_code_;
  std::optional<double> cpu_seconds_, kernel_seconds_;
  std::optional<std::uint64_t> peak_memory_bytes_;
  std::atomic<bool> stop_reading_{false};
  mutable std::mutex mutex_;  // guards the two below
  std::condition_variable output_changed_;
  std::string output_;
  bool eof_ = false;
  std::thread reader_;
};

// Starts `argv` and waits for its line "<what> listening on HOST:PORT" (what `farm worker` and
// `farm scheduler` print); returns HOST:PORT, empty when it did not come within `timeout`.
std::string wait_for_listening(ChildProcess& process, const std::string& what, std::chrono::milliseconds timeout);

}  // namespace farm
