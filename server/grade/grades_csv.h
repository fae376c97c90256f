#pragma once
// grades.csv: the class's points in one table, for the course's grade book.
//   student,<task 1>,<task 2>,...,total,maximum
// One record per student, sorted by id (byte order), tasks in rubric order; points as
// format_points prints them (60, 37.5, 12.25), a task the student has no grade for left empty;
// `maximum` is the rubric's. RFC 4180 quoting (csv_field.h), records ended by CRLF.
#include <filesystem>
#include <string>

#include "server/grade/grade_outcome.h"

namespace farm {

// The table as text.
std::string grades_csv(const ClassGrades& grades);

// Writes <dir>/grades.csv atomically and returns its path.
std::filesystem::path write_grades_csv(const ClassGrades& grades, const std::filesystem::path& dir);

}  // namespace farm
