#include "server/grade/grade_rubric.h"

#include <fmt/format.h>

#include <set>

#include "renderer/compare/compare_spec.h"
#include "renderer/util/input_error.h"
#include "renderer/util/json_reader.h"
#include "server/common/suite_file.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxTasks = 1000;

Visibility read_visibility(const JsonValue& v) {
  const std::string text = v.string();
  for (Visibility candidate : {Visibility::visible, Visibility::hidden, Visibility::after_due_date, Visibility::after_published})
    if (to_string(candidate) == text) return candidate;
  v.fail(fmt::format("unknown visibility '{}' (expected visible, hidden, after_due_date or after_published)", text));
}

std::vector<std::string> read_argv(const JsonValue& v) {
  std::vector<std::string> argv;
  for (const JsonValue& item : v.array()) {
    std::string arg = item.string();
    if (arg.find('\0') != std::string::npos) item.fail("a NUL character");
    argv.push_back(std::move(arg));
  }
  if (argv.empty() || argv[0].empty()) v.fail("a command needs at least the program to run");
  if (argv.size() > 256) v.fail("more than 256 arguments");
  return argv;
}

// A path inside a student's folder: relative, and never climbing out of it.
fs::path read_student_path(const JsonValue& v) {
  const fs::path path = fs::path(v.string()).lexically_normal();
  if (path.empty() || path.is_absolute() || *path.begin() == ".." || path == ".") {
    v.fail(fmt::format("'{}' must be a path inside the student's folder", v.string()));
  }
  return path;
}

ScoreRule read_score(const JsonValue& v) {
  std::vector<std::string_view> keys = compare_keys();
  keys.push_back("full");
  keys.push_back("zero");
  const JsonObject o = v.object(keys);
  ScoreRule rule;
  rule.compare = read_compare_settings(o, CompareSettings{});
  const auto full = o.get("full"), zero = o.get("zero");
  if (full.has_value() != zero.has_value()) v.fail("give both full and zero, or neither");
  if (full) {
    rule.full = full->real();
    rule.zero = zero->real();
    if (*rule.full == *rule.zero) zero->fail("must differ from full");
  }
  return rule;
}

}  // namespace

std::string_view to_string(Visibility visibility) {
  switch (visibility) {
    case Visibility::visible: return "visible";
    case Visibility::hidden: return "hidden";
    case Visibility::after_due_date: return "after_due_date";
    case Visibility::after_published: return "after_published";
  }
  return "visible";
}

std::string ScoreRule::figure() const {
  switch (compare.metric) {
    case Metric::exact: return "differing_percent";
    case Metric::threshold: return "failing_percent";
    case Metric::psnr: return "psnr_db";
    case Metric::ssim: return "ssim";
    case Metric::flip: return "flip_mean";
    case Metric::ztest: return "pass_percent";
  }
  return "";
}

double Rubric::max_points() const {
  double sum = 0.0;
  for (const GradeTask& t : tasks) sum += t.points;
  return sum;
}

Rubric load_rubric(const fs::path& file) {
  Rubric rubric;
  rubric.file = fs::weakly_canonical(fs::absolute(file));
  rubric.folder = rubric.file.parent_path();
  const std::string name = file.string();
  const nlohmann::json doc = parse_json_strict(read_bounded_text(file), name);
  const JsonValue root(doc, "", name);
  const JsonObject top = root.object({"version", "name", "asset_root", "tasks"});
  top.require("version").int32(1, 1);
  const JsonValue rubric_name = top.require("name");
  rubric.name = rubric_name.string();
  if (!is_safe_name(rubric.name)) rubric_name.fail("a name of letters, digits, '-', '_' and '.' (it names the output folder)");
  rubric.asset_root = read_folder(top.get("asset_root"), rubric.folder);

  const JsonValue tasks = top.require("tasks");
  const std::vector<JsonValue> items = tasks.array();
  if (items.empty()) tasks.fail("a rubric needs at least one task");
  if (items.size() > kMaxTasks) tasks.fail(fmt::format("more than {} tasks", kMaxTasks));
  std::set<std::string> names;
  for (const JsonValue& item : items) {
    const JsonObject t = item.object({"name", "points", "job", "file", "run", "output", "score", "visibility"});
    GradeTask task;
    const JsonValue task_name = t.require("name");
    task.name = task_name.string();
    if (!is_safe_name(task.name)) task_name.fail("a name of letters, digits, '-', '_' and '.'");
    if (!names.insert(task.name).second) task_name.fail(fmt::format("a second task named '{}'", task.name));
    task.points = t.require("points").real(NumberRange{0.0, 1e6, true, false});
    task.job = read_job_path(t.require("job"), rubric.folder);
    const auto file_key = t.get("file"), run_key = t.get("run");
    if (file_key.has_value() == run_key.has_value()) item.fail("a task needs either \"file\" (an image handed in) or \"run\" (a program to run)");
    if (file_key) task.file = read_student_path(*file_key);
    if (run_key) {
      const JsonObject r = run_key->object({"command", "build", "time_limit_s", "memory_mib"});
      RunSpec run;
      run.command = read_argv(r.require("command"));
      if (auto b = r.get("build")) run.build = read_argv(*b);
      if (auto x = r.get("time_limit_s")) run.time_limit_s = x->real(NumberRange{0.0, 3600.0, true, false});
      if (auto x = r.get("memory_mib")) run.memory_mib = x->int32(16, 65536);
      task.run = run;
    }
    if (auto o = t.get("output")) {
      const std::string ext = o->string();
      if (ext != "png" && ext != "exr") o->fail(fmt::format("expected png or exr, not '{}'", ext));
      if (!task.run) o->fail("\"output\" applies to a task that runs a program");
      task.run->output_extension = ext;
    }
    task.score = read_score(t.require("score"));
    if (auto v = t.get("visibility")) task.visibility = read_visibility(*v);
    rubric.tasks.push_back(std::move(task));
  }
  return rubric;
}

}  // namespace farm
