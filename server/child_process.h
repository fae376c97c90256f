#pragma once
// A child process (a `farm worker` or `farm scheduler` started by a test or by `farm bench farm`),
// its stdout and stderr read through a pipe. Every wait is bounded by a timeout; the destructor
// kills and reaps a child still running.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
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
  // Everything read so far.
  const std::string& output() const { return output_; }

  void send_signal(int signal);
  // The exit code (128 + signal for a killed child), or nullopt if it is still running after
  // `timeout`. Output keeps being drained meanwhile.
  std::optional<int> wait_exit(std::chrono::milliseconds timeout);

 private:
  // Appends what is available within `timeout`; false at end of output.
  bool read_some(std::chrono::milliseconds timeout);

  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool eof_ = false;
  std::optional<int> exit_code_;
  std::string output_;
};

// Starts `argv` and waits for its line "<what> listening on HOST:PORT" (what `farm worker` and
// `farm scheduler` print); returns HOST:PORT, empty when it did not come within `timeout`.
std::string wait_for_listening(ChildProcess& process, const std::string& what, std::chrono::milliseconds timeout);

}  // namespace farm
