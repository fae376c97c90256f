#pragma once
// The `farm` commands as a table: each command file adds its CLI11 (sub)command, binds its
// options and registers a runner here; main parses once and runs the runner of the command that
// was given. A runner owns its options (captured in the closure), so nothing outlives the table.
#include <CLI/CLI.hpp>

#include <functional>
#include <vector>

namespace farm {

class CommandTable {
 public:
  // Runs a parsed command; returns its exit code. Throws InputError for bad input (exit 2),
  // ServiceError when a server cannot be reached (1), anything else for an internal error (1).
  using Runner = std::function<int()>;

  // `command` runs `runner` when the parse picks it. Only leaves get runners: `bench` itself
  // requires one of its sub-commands.
  void add(CLI::App* command, Runner runner);

  // Runs the runner of the one command the parse picked. Throws std::logic_error when none was
  // (a command added to the app without a runner).
  int run_parsed() const;

 private:
  struct Entry {
    CLI::App* command;
    Runner runner;
  };
  std::vector<Entry> entries_;
};

}  // namespace farm
