#include "server/grade/grade_reports.h"

#include "renderer/util/thread_pool.h"
#include "server/grade/feedback_pages.h"
#include "server/grade/grades_csv.h"
#include "server/grade/gradescope_results.h"
#include "server/grade/similar_submissions.h"
#include "server/grade/class_summary.h"

namespace farm {

void write_grade_reports(const ClassGrades& grades, const std::filesystem::path& dir) {
  write_grades_csv(grades, dir);
  write_feedback_pages(grades, dir);
  write_gradescope_results(grades, dir);
  write_class_summary(grades, dir);
  ThreadPool pool(0);  // FLIP of the pairs the prefilters leave, on every core
  SimilarityOptions similarity;
  similarity.pool = &pool;
  write_similar_submissions(grades, dir, similarity);
}

}  // namespace farm
