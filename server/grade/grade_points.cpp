#include "server/grade/grade_points.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "server/common/markup_escape.h"

namespace farm {

double round_points(double points) {
  if (!std::isfinite(points)) return points;
  const double rounded = std::round(points * 100.0) / 100.0;
  return rounded == 0.0 ? 0.0 : rounded;  // no negative zero
}

std::string format_points(double points) {
  if (!std::isfinite(points)) return format_figure(points);
  std::string text = fmt::format("{:.2f}", round_points(points));
  while (text.back() == '0') text.pop_back();
  if (text.back() == '.') text.pop_back();
  return text == "-0" ? "0" : text;
}

double StudentGrade::total() const {
  double sum = 0.0;
  for (const TaskGrade& task : tasks) sum += task.points;
  return sum;
}

double points_total(const StudentGrade& student) { return student.total(); }

double points_maximum(const StudentGrade& student) {
  double maximum = 0.0;
  for (const TaskGrade& task : student.tasks) maximum += task.max_points;
  return maximum;
}

double points_maximum(const ClassGrades& grades) {
  double maximum = 0.0;
  if (grades.rubric != nullptr) {
    for (const GradeTask& task : grades.rubric->tasks) maximum += task.points;
    return maximum;
  }
  for (const StudentGrade& student : grades.students) maximum = std::max(maximum, points_maximum(student));
  return maximum;
}

std::vector<std::string> grade_task_names(const ClassGrades& grades) {
  std::vector<std::string> names;
  if (grades.rubric != nullptr) {
    for (const GradeTask& task : grades.rubric->tasks) names.push_back(task.name);
  } else if (!grades.students.empty()) {
    for (const TaskGrade& task : grades.students.front().tasks) names.push_back(task.task);
  }
  return names;
}

const TaskGrade* find_task(const StudentGrade& student, const std::string& task) {
  for (const TaskGrade& t : student.tasks)
    if (t.task == task) return &t;
  return nullptr;
}

}  // namespace farm
