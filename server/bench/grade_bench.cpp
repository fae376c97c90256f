#include "server/bench/grade_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <random>

#include "renderer/compare/image.h"
#include "server/bench/bench_support.h"
#include "server/client/job_submission.h"
#include "server/common/scene_hash.h"
#include "server/grade/grade_reports.h"
#include "server/grade/grade_runner.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using bench::seconds_since;
using Clock = std::chrono::steady_clock;


// Student `i`'s version of a reference: every fourth one perfect, the others noisy, shifted by a
// pixel or 5% darker, each with its own noise.
Image student_image(const Image& reference, int i) {
  Image out = reference;
  std::mt19937 rng(static_cast<std::uint32_t>(i));
  std::normal_distribution<float> noise(0.0f, 0.02f);
  const int kind = i % 4;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (std::size_t c = 0; c < out.channel_count(); ++c) {
        const int ch = static_cast<int>(c);
        float v = reference.at(kind == 2 ? std::max(0, x - 1) : x, y, ch);
        if (kind == 1) v += noise(rng);
        if (kind == 3) v *= 0.95f;
        out.at(x, y, ch) = std::clamp(v, 0.0f, 1.0f);
      }
  return out;
}

}  // namespace

void run_grade_bench(const GradeBenchOptions& o) {
  const Rubric rubric = load_rubric(o.rubric);
  const bench::ScratchDir scratch("bench-grade");
  GradeOptions options;
  options.jobs = o.jobs;
  options.output_dir = scratch.path() / "grades";
  fs::create_directories(scratch.path() / "empty");

  // The references, rendered once (a class of nobody renders them).
  const Clock::time_point start = Clock::now();
  grade_class(rubric, scratch.path() / "empty", options);
  const double references = seconds_since(start);

  // The class: each file task's image from that task's reference preview.
  std::size_t file_tasks = 0;
  for (const GradeTask& task : rubric.tasks) {
    if (!task.file) continue;
    ++file_tasks;
    JobLoadOptions load;
    load.asset_root = rubric.asset_root;
    const std::string hash = scene_hash(make_job_submission(task.job, load, {}).spec);
    const Image reference = read_image(options.output_dir / "references" / hash / "reference.png");
    for (int i = 0; i < o.students; ++i) {
      write_png_image(student_image(reference, i), scratch.path() / "class" / fmt::format("student{:03}", i) / *task.file);
    }
  }
  const Clock::time_point graded = Clock::now();
  const ClassGrades grades = grade_class(rubric, scratch.path() / "class", options);
  const double grading = seconds_since(graded);
  const Clock::time_point reported = Clock::now();
  write_grade_reports(grades, options.output_dir);
  const double reports = seconds_since(reported);
  double total = 0.0;
  for (const StudentGrade& s : grades.students) total += s.total();
  fmt::print("farm bench grade ({}): {} ({} image tasks), {} students\n", bench::machine_summary(),
             o.rubric.string(), file_tasks, o.students);
  fmt::print("references rendered once   {:8.2f} s\n", references);
  fmt::print("grading {} students        {:8.2f} s   ({:.1f} ms a student, mean score {:.1f} of {:g})\n", o.students,
             grading, 1000.0 * grading / std::max(1, o.students), total / static_cast<double>(std::max<std::size_t>(1, grades.students.size())),
             rubric.max_points());
  fmt::print("reports (csv, feedback, gradescope, summary, similar) {:6.2f} s\n", reports);
  fmt::print("in all                     {:8.2f} s\n", references + grading + reports);
}

}  // namespace farm
