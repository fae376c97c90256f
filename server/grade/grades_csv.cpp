#include "server/grade/grades_csv.h"

#include <algorithm>

#include "renderer/util/atomic_file.h"
#include "server/grade/csv_field.h"
#include "server/grade/grade_points.h"

namespace farm {

std::string grades_csv(const ClassGrades& grades) {
  const std::vector<std::string> tasks = grade_task_names(grades);
  std::vector<std::string> header{"student"};
  header.insert(header.end(), tasks.begin(), tasks.end());
  header.push_back("total");
  header.push_back("maximum");
  std::string csv = csv_record(header);

  std::vector<const StudentGrade*> order;
  for (const StudentGrade& s : grades.students) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(),
                   [](const StudentGrade* a, const StudentGrade* b) { return a->student < b->student; });
  const std::string maximum = format_points(points_maximum(grades));
  for (const StudentGrade* s : order) {
    std::vector<std::string> record{s->student};
    for (const std::string& task : tasks) {
      const TaskGrade* t = find_task(*s, task);
      record.push_back(t != nullptr ? format_points(t->points) : std::string());
    }
    record.push_back(format_points(points_total(*s)));
    record.push_back(maximum);
    csv += csv_record(record);
  }
  return csv;
}

std::filesystem::path write_grades_csv(const ClassGrades& grades, const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "grades.csv";
  write_text_atomically(file, grades_csv(grades));
  return file;
}

}  // namespace farm
