#pragma once
// `farm bench raster|rt|path|farm`: the options of the benchmarks; the benchmarks themselves are
// in server/bench/.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm bench` with its four sub-commands to `app` and their runners to `commands`.
void add_bench_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
