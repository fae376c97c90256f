#pragma once
// Runs a command line in a shell for tests that drive the real `farm` binary.
#include <string>

namespace farm::test {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

CommandResult run_command(const std::string& command_line);

// Quotes one argument for /bin/sh.
std::string shell_quote(const std::string& arg);

// The `farm` binary under test followed by `args` (already quoted as needed).
std::string farm_command(const std::string& args);

}  // namespace farm::test
