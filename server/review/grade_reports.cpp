#include "server/review/grade_reports.h"

#include "renderer/util/thread_pool.h"
#include "server/review/class_summary.h"
#include "server/review/feedback_pages.h"
#include "server/review/grades_csv.h"
#include "server/review/gradescope_results.h"
#include "server/review/similar_submissions.h"

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
