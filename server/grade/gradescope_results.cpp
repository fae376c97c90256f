#include "server/grade/gradescope_results.h"

#include <fmt/format.h>

#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/grade/grade_points.h"
#include "server/grade/student_folder.h"

namespace farm {
namespace {

// A test's output: the reason, the metric's figures, and the program's output when there is one.
std::string test_output(const TaskGrade& t) {
  std::string out = t.reason;
  if (t.compared && !t.result.figures.empty()) {
    out += "\n";
    for (const Figure& f : t.result.figures) out += fmt::format("\n{}: {}", f.name, format_figure(f.value));
  }
  if (!t.program_output.empty()) out += "\n\nprogram output:\n" + t.program_output;
  return out;
}

}  // namespace

std::string gradescope_visibility(Visibility visibility) { return std::string(to_string(visibility)); }

nlohmann::ordered_json gradescope_results_json(const StudentGrade& student) {
  nlohmann::ordered_json tests = nlohmann::ordered_json::array();
  double score = 0.0, maximum = 0.0;
  for (const TaskGrade& t : student.tasks) {
    const double points = round_points(t.points), max_points = round_points(t.max_points);
    score += points;
    maximum += max_points;
    tests.push_back({{"name", t.task},
                     {"name_format", "text"},
                     {"score", points},
                     {"max_score", max_points},
                     {"status", points >= max_points ? "passed" : "failed"},
                     {"output", test_output(t)},
                     {"output_format", "text"},
                     {"visibility", gradescope_visibility(t.visibility)}});
  }
  nlohmann::ordered_json results;
  results["score"] = round_points(score);
  results["execution_time"] = round_points(student.seconds);
  results["output"] = fmt::format("{} / {} points over {} task{}", format_points(score), format_points(maximum),
                                  student.tasks.size(), student.tasks.size() == 1 ? "" : "s");
  results["output_format"] = "text";
  results["test_output_format"] = "text";
  results["test_name_format"] = "text";
  results["visibility"] = "visible";
  results["stdout_visibility"] = "hidden";
  results["tests"] = std::move(tests);
  return results;
}

void write_gradescope_results(const StudentGrade& student, const std::filesystem::path& file) {
  // JSON holds UTF-8 only and program output can be any bytes: invalid ones become U+FFFD rather
  // than failing the whole file.
  write_text_atomically(file,
                    gradescope_results_json(student).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

std::vector<std::filesystem::path> write_gradescope_results(const ClassGrades& grades, const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const StudentGrade& s : grades.students) {
    files.push_back(dir / "gradescope" / student_folder_name(s.student) / "results.json");
    write_gradescope_results(s, files.back());
  }
  return files;
}

}  // namespace farm
