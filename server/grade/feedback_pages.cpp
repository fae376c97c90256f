#include "server/grade/feedback_pages.h"

#include <fmt/format.h>

#include <set>
#include <stdexcept>

#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/grade/grade_points.h"
#include "server/grade/student_folder.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFeedbackPageStyle = R"(
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em; color: #222; max-width: 1100px; }
h1 { margin-bottom: 0.2em; } .total { font-size: 18px; margin-bottom: 1.5em; } .rubric { color: #555; }
.task { border: 1px solid #ccc; border-radius: 6px; margin: 1em 0; padding: 0.8em 1em; }
.full { border-left: 8px solid #2e7d32; } .partial { border-left: 8px solid #ef8f00; } .none { border-left: 8px solid #c62828; }
.task h2 { font-size: 16px; margin: 0 0 0.4em 0; } .points { margin-left: 0.8em; font-weight: normal; }
.hidden-note { color: #8a4b00; font-weight: normal; font-size: 13px; margin-left: 0.6em; }
.reason { margin: 0.4em 0; } table { border-collapse: collapse; margin: 0.4em 0; }
td { padding: 1px 10px 1px 0; font-family: monospace; }
.images { display: flex; gap: 12px; flex-wrap: wrap; } figure { margin: 0; }
figure img { width: 320px; height: auto; image-rendering: pixelated; border: 1px solid #ddd; display: block; }
figcaption { color: #555; font-size: 12px; } .missing { color: #777; font-style: italic; }
pre { background: #f6f6f6; border: 1px solid #ddd; padding: 0.6em; overflow-x: auto; white-space: pre-wrap; }
)";

const char* standing(const TaskGrade& t) {
  const double points = round_points(t.points);
  if (points >= round_points(t.max_points)) return "full";
  return points > 0.0 ? "partial" : "none";
}

// Copies one of the task's PNGs into the student's folder and returns its <figure>, or a note
// when the runner named a file that is not there. Nothing when the task has no such image.
std::string figure(const fs::path& source, const fs::path& folder, const std::string& stem, const char* kind,
                   const std::string& caption) {
  if (source.empty()) return {};
  const std::string name = fmt::format("{}.{}.png", stem, kind);
  std::error_code ec;
  if (!fs::is_regular_file(source, ec)) {
    return fmt::format("<figure><div class=\"missing\">{} image not available</div></figure>\n", kind);
  }
  copy_file_atomically(source, folder / name);
  return fmt::format("<figure><img src=\"{0}\" alt=\"{1}\"><figcaption>{1}</figcaption></figure>\n",
                     markup_escape(url_path_segment(name)), markup_escape(caption));
}

std::string task_section(const TaskGrade& t, const fs::path& folder) {
  const std::string stem = student_folder_name(t.task);
  std::string html = fmt::format("<section class=\"task {}\" id=\"{}\"><h2>{}<span class=\"points\">{} / {}</span>",
                                 standing(t), markup_escape(t.task), markup_escape(t.task), format_points(t.points),
                                 format_points(t.max_points));
  if (t.visibility != Visibility::visible) html += fmt::format("<span class=\"hidden-note\">{}</span>", kHiddenTaskNote);
  html += "</h2>\n";
  html += fmt::format("<div class=\"reason\">{}</div>\n", markup_escape(t.reason));
  if (t.compared && !t.result.figures.empty()) {
    html += "<table>\n";
    for (const Figure& f : t.result.figures)
      html += fmt::format("<tr><td>{}</td><td>{}</td></tr>\n", markup_escape(f.name), format_figure(f.value));
    html += "</table>\n";
  }
  const std::string difference =
      t.compared ? fmt::format("difference ({})", to_string(t.result.metric)) : std::string("difference");
  const std::string images = figure(t.student_png, folder, stem, "student", "your image") +
                             figure(t.reference_png, folder, stem, "reference", "reference") +
                             figure(t.difference_png, folder, stem, "difference", difference);
  if (!images.empty()) html += "<div class=\"images\">\n" + images + "</div>\n";
  if (!t.program_output.empty())
    html += fmt::format("<div>program output:</div>\n<pre>{}</pre>\n", markup_escape(t.program_output));
  html += "</section>\n";
  return html;
}

}  // namespace

fs::path write_feedback_page(const StudentGrade& student, const Rubric* rubric, const fs::path& folder) {
  const std::string id = markup_escape(student.student);
  std::string html = fmt::format("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                                 "<title>Feedback: {0}</title><style>{1}</style></head><body>\n"
                                 "<h1>Feedback: {0}</h1>\n",
                                 id, kFeedbackPageStyle);
  if (rubric != nullptr && !rubric->name.empty())
    html += fmt::format("<div class=\"rubric\">{}</div>\n", markup_escape(rubric->name));
  html += fmt::format("<div class=\"total\">Total: <b>{} / {}</b> points</div>\n", format_points(points_total(student)),
                      format_points(points_maximum(student)));
  for (const TaskGrade& t : student.tasks) html += task_section(t, folder);
  html += "</body></html>\n";
  const fs::path page = folder / "index.html";
  write_text_atomically(page, html);
  return page;
}

std::vector<fs::path> write_feedback_pages(const ClassGrades& grades, const fs::path& dir) {
  std::set<std::string> seen;
  for (const StudentGrade& s : grades.students)
    if (!seen.insert(s.student).second)
      throw std::invalid_argument(fmt::format("two students share the id \"{}\"", s.student));
  std::vector<fs::path> pages;
  for (const StudentGrade& s : grades.students)
    pages.push_back(write_feedback_page(s, grades.rubric, dir / "feedback" / student_folder_name(s.student)));
  return pages;
}

}  // namespace farm
