#pragma once
// `farm regress SUITE.json`: renders a regression suite on the farm and compares every image
// with its reference (server/regress/), with console lines, JUnit XML and an HTML report.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm regress` to `app` and its runner to `commands`.
void add_regress_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
