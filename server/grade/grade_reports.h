#pragma once
// Everything `farm grade` writes for a class, in one call: grades.csv, feedback/<student>/,
// gradescope/<student>/results.json, summary.html (with its histogram picture) and similar.csv.
#include <filesystem>

#include "server/grade/grade_outcome.h"

namespace farm {

void write_grade_reports(const ClassGrades& grades, const std::filesystem::path& dir);

}  // namespace farm
