#include "server/cli/grade_command.h"

#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "renderer/job/job_limits.h"
#include "renderer/util/input_error.h"
#include "server/cli/progress_bar.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"
#include "server/grade/grade_reports.h"
#include "server/grade/grade_runner.h"
#include "server/grade/gradescope_results.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct GradeCommandOptions {
  fs::path rubric;
  std::optional<fs::path> submissions;
  std::optional<fs::path> out;
  std::optional<std::string> scheduler;
  SchedulerConnectionFlags identity;  // --token-file, --tls-*: used with --scheduler
  int jobs = 0;
  int threads = 0;
  bool gradescope = false;
  bool keep_work = false;
  fs::path gradescope_root = "/autograder";
};

// "alice        85 / 100   cow 60, cow-depth-order 20, program 5"
std::string student_line(const StudentGrade& s, double maximum) {
  std::string tasks;
  for (const TaskGrade& t : s.tasks) tasks += fmt::format("{}{} {:g}", tasks.empty() ? "" : ", ", t.task, t.points);
  return fmt::format("{:<16} {:>6.4g} / {:<6g} {}", s.student, s.total(), maximum, tasks);
}

int run_grade_command(const GradeCommandOptions& o) {
  const Rubric rubric = load_rubric(o.rubric);
  GradeOptions options;
  options.jobs = o.jobs;
  options.threads = o.threads;
  options.keep_work = o.keep_work;
  options.scheduler = resolve_optional_scheduler(o.scheduler, o.identity);

  if (o.gradescope) {
    // Inside Gradescope's container: the one submission, the one results file.
    options.output_dir = o.out ? *o.out : o.gradescope_root / "grading";
    const StudentGrade student = grade_submission(rubric, o.gradescope_root / "submission", "submission", options);
    const fs::path results = o.gradescope_root / "results" / "results.json";
    write_gradescope_results(student, results);
    fmt::print("{}\nwrote {}\n", student_line(student, rubric.max_points()), results.string());
    return 0;
  }
  if (!o.submissions) throw InputError("SUBMISSIONS: give the folder of submissions (one folder per student)");
  options.output_dir = o.out ? *o.out : fs::path("grades") / rubric.name;
  ProgressBar bar(rubric.name, ProgressBar::stderr_is_terminal());
  GradeEvents events;
  events.graded = [&](const StudentGrade& s) {
    bar.clear();
    fmt::print("{}\n", student_line(s, rubric.max_points()));
    std::fflush(stdout);
  };
  events.progress = [&](std::size_t done, std::size_t total) { bar.update(done, total); };
  const ClassGrades grades = grade_class(rubric, *o.submissions, options, events);
  write_grade_reports(grades, options.output_dir);
  fmt::print("{} students graded; grades.csv, summary.html, similar.csv, feedback/ and gradescope/ in {}\n",
             grades.students.size(), options.output_dir.string());
  return 0;
}

}  // namespace

void add_grade_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<GradeCommandOptions>();
  CLI::App* grade = app.add_subcommand(
      "grade", "Score a class's submissions against farm-rendered references by a rubric (jobs/grade/README.md)");
  grade->add_option("RUBRIC", o->rubric, "The rubric file (JSON)")->required();
  grade->add_option("SUBMISSIONS", o->submissions, "A folder with one folder per student (its name is the student id)");
  grade->add_option("--out", o->out, "Where the grades go (default grades/<rubric name>/)");
  grade->add_option("--scheduler", o->scheduler, "Render the references on this scheduler (HOST:PORT)");
  add_client_identity_options(*grade, o->identity);
  grade->add_option("--jobs", o->jobs, "Students graded at a time (default: one per core)")->check(CLI::Range(0, 256));
  grade->add_option("--threads", o->threads, "Embedded farm render threads (default: all cores)")
      ->check(CLI::Range(0, kMaxThreads));
  grade->add_flag("--keep-work", o->keep_work,
                  "Keep each program's work copy (OUT/work/STUDENT/TASK/, up to 1 GiB each) after it is graded, to "
                  "look into it; by default only the pictures the feedback shows are kept");
  grade->add_flag("--gradescope", o->gradescope,
                  "Grade the one submission in /autograder/submission and write /autograder/results/results.json "
                  "(inside Gradescope's autograder; deploy/gradescope/run_autograder)");
  grade->add_option("--gradescope-root", o->gradescope_root, "The autograder folder for --gradescope")->capture_default_str();
  grade->footer("Exit codes: 0 graded (whatever the scores), 1 an internal error, 2 a bad rubric or a missing folder.");
  commands.add(grade, [o] { return run_grade_command(*o); });
}

}  // namespace farm
