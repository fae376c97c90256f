#pragma once
// `farm grade RUBRIC SUBMISSIONS`: scores a class's submissions against farm-rendered references
// (server/grade/), with grades.csv, feedback pages, Gradescope results, a class summary and a
// list of near-identical submissions; `--gradescope` grades one submission inside Gradescope's
// autograder container.
#include "server/cli/command_table.h"

namespace farm {

void add_grade_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
