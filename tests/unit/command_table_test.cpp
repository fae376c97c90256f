// The table that `farm` dispatches through: the runner of the command the parse picked runs,
// and only that one.
#include <gtest/gtest.h>

#include <stdexcept>

#include "server/cli/command_table.h"

namespace farm {
namespace {

TEST(CommandTable, RunsTheRunnerOfTheParsedSubcommandOnly) {
  CLI::App app;
  CommandTable commands;
  int ran_a = 0, ran_b = 0;
  commands.add(app.add_subcommand("a"), [&] {
    ++ran_a;
    return 3;
  });
  CLI::App* group = app.add_subcommand("group");
  commands.add(group->add_subcommand("b"), [&] {
    ++ran_b;
    return 4;
  });
  app.parse("group b", false);
  EXPECT_EQ(commands.run_parsed(), 4);
  EXPECT_EQ(ran_a, 0);
  EXPECT_EQ(ran_b, 1);
}

TEST(CommandTable, ACommandWithoutARunnerIsAnInternalError) {
  CLI::App app;
  CommandTable commands;
  commands.add(app.add_subcommand("a"), [] { return 0; });
  app.add_subcommand("forgotten");
  app.parse("forgotten", false);
  EXPECT_THROW(commands.run_parsed(), std::logic_error);
}

}  // namespace
}  // namespace farm
