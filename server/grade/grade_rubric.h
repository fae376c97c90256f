#pragma once
// A grading rubric (JSON, version 1; jobs/grade/README.md): the tasks a class's submissions are
// scored on. Each task compares one image a student handed in (`file`) or one their program
// writes (`run`) with the reference the farm renders for `job`, and turns a metric into points.
// Read strictly, like job files: every error names the file and the JSON path.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "renderer/compare/compare_settings.h"

namespace farm {

// Gradescope's test visibility values.
enum class Visibility { visible, hidden, after_due_date, after_published };
std::string_view to_string(Visibility visibility);  // "visible", "hidden", "after_due_date", "after_published"

// How a metric becomes points. With `full` and `zero`, points fall linearly from all at `full`
// to none at `zero` (lower-is-better when full < zero, higher-is-better otherwise), clamped;
// without them the metric's PASS (or WARN) earns all points and FAIL none.
struct ScoreRule {
  CompareSettings compare;
  std::optional<double> full, zero;
  // The figure `full` and `zero` are read against: flip_mean, psnr_db, ssim, mean_error, ...
  std::string figure() const;
};

// A student program run in the sandbox: `build` first (when given) in a private work folder
// holding a copy of the submission, then `command` with {job} and {output} replaced.
struct RunSpec {
  std::vector<std::string> command;
  std::vector<std::string> build;
  double time_limit_s = 60.0;
  int memory_mib = 2048;
  std::string output_extension = "png";  // "png" or "exr": what {output} is named
};

struct GradeTask {
  std::string name;           // unique; [A-Za-z0-9._-]
  double points = 0.0;        // > 0
  std::filesystem::path job;  // absolute
  std::optional<std::filesystem::path> file;  // relative to a student's folder (no .., not absolute)
  std::optional<RunSpec> run;                 // exactly one of file and run
  ScoreRule score;
  Visibility visibility = Visibility::visible;
};

struct Rubric {
  std::filesystem::path file;        // absolute
  std::string name;
  std::filesystem::path folder;      // the rubric's folder
  std::filesystem::path asset_root;  // models the jobs read must lie inside
  std::vector<GradeTask> tasks;
  double max_points() const;
};

Rubric load_rubric(const std::filesystem::path& file);

}  // namespace farm
