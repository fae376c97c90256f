#pragma once
// Points as the grade reports print and add them: every report (grades.csv, feedback pages,
// Gradescope results, the class summary) shows the same figures the same way.
#include <string>
#include <vector>

#include "server/grade/grade_outcome.h"

namespace farm {

// Rounded to 2 decimals with no trailing zeros: 60, 37.5, 12.25, 0 (never "-0"). Points are
// never NaN or infinite (the runner clamps them); such a value prints as format_figure does.
std::string format_points(double points);

// Rounded to 2 decimals as a number (what format_points prints), for JSON.
double round_points(double points);

// The sum of a student's task points and of their tasks' maximum points. (The reports add these
// themselves rather than call StudentGrade::total() and Rubric::max_points(), so that they need
// nothing from the runner beyond the structures it fills.)
double points_total(const StudentGrade& student);
double points_maximum(const StudentGrade& student);

// The class's maximum: the rubric's task points added up, or, without a rubric, the largest
// student maximum.
double points_maximum(const ClassGrades& grades);

// The task names in rubric order: the rubric's, or without a rubric, the first student's.
std::vector<std::string> grade_task_names(const ClassGrades& grades);

// The student's grade for `task`, or null when the student has none.
const TaskGrade* find_task(const StudentGrade& student, const std::string& task);

}  // namespace farm
