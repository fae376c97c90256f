#pragma once
// What grading gave: per student and task the points, the reason in words a student
// understands, the figures, and the files the feedback shows. The reports (grades.csv, feedback
// pages, Gradescope results, the class summary, similar submissions) are written from this.
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/compare/compare.h"
#include "server/grade/grade_rubric.h"

namespace farm {

struct TaskGrade {
  std::string task;
  double points = 0.0, max_points = 0.0;
  Visibility visibility = Visibility::visible;
  // "FLIP mean 0.12: 0.05 earns all 60 points, 0.25 none" or, when nothing could be compared,
  // why: "cow.png: expected 640x480, got 800x600", "the program ran past its 60 s limit".
  std::string reason;
  bool compared = false;           // `result` holds the comparison's figures
  CompareResult result;
  // Display PNGs for the feedback page (absolute; empty when there is none).
  std::filesystem::path student_png, reference_png, difference_png;
  std::string program_output;      // run tasks: the build's and the program's output, truncated
  double seconds = 0.0;
};

struct StudentGrade {
  std::string student;             // the submission folder's name
  std::vector<TaskGrade> tasks;    // in rubric order
  double seconds = 0.0;
  double total() const;
};

struct ClassGrades {
  const Rubric* rubric = nullptr;
  std::vector<StudentGrade> students;  // sorted by student id
};

}  // namespace farm
