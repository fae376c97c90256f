#pragma once
// Gradescope autograder results (results.json), one per student, as Gradescope's "Autograder
// Specifications" define them (https://gradescope-autograders.readthedocs.io/en/latest/specs/,
// "Output format", "Controlling Test Case Visibility", "Test case status" and "Output String
// Formatting"; the page's source is docs/specs.md of github.com/gradescope/autograder_samples):
//
//   { "score": 37.5,                 total points (overrides the sum of the tests)
//     "execution_time": 12.34,       seconds
//     "output": "37.5 / 100 points over 3 tasks",
//     "output_format": "text",       the default for the top-level output is "simple_format",
//     "test_output_format": "text",  which renders HTML: ours holds hostile text, so plain text
//     "test_name_format": "text",
//     "visibility": "visible", "stdout_visibility": "hidden",
//     "tests": [ { "name": "cow", "score": 37.5, "max_score": 60, "status": "failed",
//                  "output": "<reason>...", "output_format": "text", "name_format": "text",
//                  "visibility": "visible" }, ... ] }
//
// One test per task in rubric order; "status" is "passed" when the task earned its full points,
// else "failed"; a test's visibility is the task's (hidden, after_due_date, after_published or
// visible). Scores are rounded to 2 decimals, as grades.csv prints them; the top-level score is
// the sum of the test scores shown. tests/data/gradescope/results.schema.json checks the shape.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "server/grade/grade_outcome.h"

namespace farm {

// The visibility value Gradescope reads.
std::string gradescope_visibility(Visibility visibility);  // the rubric's names are Gradescope's

nlohmann::ordered_json gradescope_results_json(const StudentGrade& student);

// Writes one student's results.json at `file` (e.g. /autograder/results/results.json inside a
// Gradescope container), atomically.
void write_gradescope_results(const StudentGrade& student, const std::filesystem::path& file);

// Writes <dir>/gradescope/<student_folder_name(id)>/results.json for every student; returns the
// files in student order.
std::vector<std::filesystem::path> write_gradescope_results(const ClassGrades& grades, const std::filesystem::path& dir);

}  // namespace farm
