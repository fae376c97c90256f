#pragma once
// Grades a class: renders each distinct scene of the rubric once (cached by scene hash under the
// output folder), then scores every student's folder task by task: an image handed in, or the
// image their program writes in the sandbox, compared with the reference and turned into points.
// A student's bad files (missing, a link out of the folder, a folder where an image should be,
// corrupt, huge, the wrong size) and a program that fails in any way cost that task's points
// with the reason; they never stop the grading of anything else.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "server/client/scheduler_connection.h"
#include "server/grade/grade_outcome.h"
#include "server/grade/grade_rubric.h"

namespace farm {

struct GradeOptions {
  std::optional<SchedulerConnection> scheduler;  // render references there instead of the embedded farm
  int jobs = 0;                          // students graded at a time (0: one per core)
  int threads = 0;                       // embedded farm render threads (0: all cores)
  std::filesystem::path output_dir;      // references/ and work/ go here
  // Keep each program's work copy (work/<student>/<task>/) once graded; by default it is removed,
  // and only the pictures the feedback shows stay in work/<student>/.
  bool keep_work = false;
};

struct GradeEvents {
  std::function<void(const StudentGrade&)> graded;  // one student, as soon as they are done
  std::function<void(std::size_t done, std::size_t total)> progress;
};

// Every folder in `submissions` is a student, its name the id.
ClassGrades grade_class(const Rubric& rubric, const std::filesystem::path& submissions, const GradeOptions& options,
                        const GradeEvents& events = {});

// One submission folder (Gradescope's /autograder/submission), graded as student `id`.
StudentGrade grade_submission(const Rubric& rubric, const std::filesystem::path& folder, const std::string& id,
                              const GradeOptions& options);

// Points for a comparison under `rule`, and the sentence that explains them.
double score_points(const ScoreRule& rule, const CompareResult& result, double max_points, std::string& reason);

}  // namespace farm
