#pragma once
// feedback/<student>/index.html: what one student is handed. A self-contained page that opens
// from disk (no scripts, no network): the student's id and total, then per task the points
// ("37.5 / 60"), the reason, the metric's figures, the student's image beside the reference and
// the difference (FLIP) map, and the program's output when there is any. The PNGs are copied into
// the student's folder, so the folder alone can be given to that student.
//
// Every task is shown, those not visible to students on Gradescope (hidden, after_due_date,
// after_published) marked "(hidden from students until published)": staff decide when to hand
// the pages out. Student ids, reasons and outputs are hostile input: all text is escaped.
// The folder is named by student_folder_name() (student_folder.h), never by the raw id.
#include <filesystem>
#include <vector>

#include "server/grade/grade_outcome.h"

namespace farm {

// The marker shown beside a task that students do not see yet.
inline constexpr const char* kHiddenTaskNote = "(hidden from students until published)";

// Writes <folder>/index.html and the task images (<task>.student.png, <task>.reference.png,
// <task>.difference.png) for one student; an image whose source file is missing is left out and
// the page says so. `rubric` may be null (its name is then not shown). Returns the page's path.
std::filesystem::path write_feedback_page(const StudentGrade& student, const Rubric* rubric,
                                          const std::filesystem::path& folder);

// Writes <dir>/feedback/<student_folder_name(id)>/ for every student; returns the pages in
// student order. Throws std::invalid_argument when two students share an id.
std::vector<std::filesystem::path> write_feedback_pages(const ClassGrades& grades, const std::filesystem::path& dir);

}  // namespace farm
