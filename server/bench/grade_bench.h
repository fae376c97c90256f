#pragma once
// `farm bench grade`: a synthetic class (perfect, noisy, shifted and darker copies of the
// references) graded by a rubric on the embedded farm: the time to render the references once,
// then the time to grade every student and to write what `farm grade` writes.
#include <filesystem>

namespace farm {

struct GradeBenchOptions {
  std::filesystem::path rubric = "jobs/grade/dandelion/rubric.json";
  int students = 100;
  int jobs = 0;  // students at a time (0: one per core)
};

void run_grade_bench(const GradeBenchOptions& options);

}  // namespace farm
