#pragma once
// `farm compare REF NEW`: one image against its reference by one metric (renderer/compare/),
// with a PASS / WARN / FAIL verdict, the figures behind it and a difference image.
#include "server/cli/command_table.h"

namespace farm {

// Adds `farm compare` to `app` and its runner to `commands`.
void add_compare_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
