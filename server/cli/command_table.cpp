#include "server/cli/command_table.h"

#include <stdexcept>
#include <utility>

namespace farm {

void CommandTable::add(CLI::App* command, Runner runner) {
  entries_.push_back({command, std::move(runner)});
}

int CommandTable::run_parsed() const {
  for (const Entry& entry : entries_) {
    if (entry.command->parsed()) return entry.runner();
  }
  throw std::logic_error("the command line named a command that has no runner");
}

}  // namespace farm
