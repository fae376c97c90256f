#include "server/grade/class_summary.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/grade/grade_points.h"
#include "server/grade/student_folder.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr const char* kHistogramFile = "summary-totals.png";
constexpr int kLostMostShown = 5;

// The plot area inside the picture: bars of kBarStep pixels (kBarGap of them blank) from kLeft.
constexpr int kLeft = 30, kBottom = 28, kTop = 12, kBarStep = 44, kBarGap = 4, kTickLength = 6;
static_assert(kLeft + kHistogramBins * kBarStep <= kHistogramWidth);

constexpr const char* kClassSummaryStyle = R"(
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em; color: #222; max-width: 1100px; }
h1 { margin-bottom: 0.2em; } .counts { color: #555; margin-bottom: 1.5em; }
table { border-collapse: collapse; margin: 0.6em 0 1.2em 0; }
th, td { padding: 2px 12px 2px 0; text-align: left; } td.n { font-family: monospace; text-align: right; }
th { border-bottom: 1px solid #ccc; } .histogram { display: flex; gap: 24px; align-items: flex-start; }
.histogram img { border: 1px solid #ddd; display: block; } .axis { color: #555; font-size: 12px; }
.axis span { display: inline-block; text-align: center; }
.reason { color: #444; } .hidden-note { color: #8a4b00; font-size: 13px; }
)";

void fill(Image& image, int x0, int y0, int x1, int y1, const float (&colour)[3]) {
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x)
      for (int c = 0; c < 3; ++c) image.at(x, y, c) = colour[c];
}

// 1, 2, 5, 10, 20, 50, ... students per y tick, so that at most 10 ticks are drawn.
int tick_step(int max_count) {
  for (int scale = 1;; scale *= 10)
    for (int m : {1, 2, 5})
      if (max_count <= 10 * m * scale) return m * scale;
}

struct Figures {
  double mean = 0.0, median = 0.0;
};

Figures figures_of(const std::vector<double>& values) {
  Figures f;
  if (values.empty()) return f;
  f.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  f.median = median_of(values);
  return f;
}

std::string student_link(const std::string& student) {
  return fmt::format("<a href=\"feedback/{}/index.html\">{}</a>",
                     markup_escape(url_path_segment(student_folder_name(student))), markup_escape(student));
}

}  // namespace

double median_of(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2.0;
}

std::vector<int> total_histogram(const ClassGrades& grades) {
  std::vector<int> counts(kHistogramBins, 0);
  const double maximum = points_maximum(grades);
  for (const StudentGrade& s : grades.students) {
    const double fraction = maximum > 0.0 ? points_total(s) / maximum : 0.0;
    const int bin = static_cast<int>(std::floor(fraction * kHistogramBins));
    ++counts[static_cast<std::size_t>(std::clamp(bin, 0, kHistogramBins - 1))];
  }
  return counts;
}

Image draw_histogram(const std::vector<int>& counts, int step) {
  static constexpr float kWhite[3] = {1.0f, 1.0f, 1.0f}, kBlack[3] = {0.0f, 0.0f, 0.0f},
                         kGrid[3] = {0.85f, 0.85f, 0.85f};
  Image image = make_image(kHistogramWidth, kHistogramHeight, {"R", "G", "B"});
  fill(image, 0, 0, kHistogramWidth, kHistogramHeight, kWhite);
  const int axis_y = kHistogramHeight - kBottom;  // the x axis's row
  const int plot_height = axis_y - kTop;
  const int plot_right = kLeft + static_cast<int>(counts.size()) * kBarStep;
  const int max_count = std::max(1, counts.empty() ? 0 : *std::max_element(counts.begin(), counts.end()));
  const auto height_of = [&](int count) {  // a bar of one student is never lost to rounding
    if (count <= 0) return 0;
    return std::max(1, static_cast<int>(std::lround(static_cast<double>(count) / max_count * plot_height)));
  };
  step = std::max(1, step);
  for (int n = step; n <= max_count; n += step) {  // grid lines and y ticks
    const int y = axis_y - height_of(n);
    fill(image, kLeft, y, plot_right, y + 1, kGrid);
    fill(image, kLeft - 1 - kTickLength, y, kLeft - 1, y + 1, kBlack);
  }
  for (std::size_t i = 0; i < counts.size(); ++i) {  // bars
    const int x = kLeft + static_cast<int>(i) * kBarStep;
    fill(image, x + kBarGap / 2, axis_y - height_of(counts[i]), x + kBarStep - kBarGap / 2, axis_y, kHistogramBar);
  }
  fill(image, kLeft - 1, kTop, kLeft, axis_y + 1, kBlack);        // y axis
  fill(image, kLeft - 1, axis_y, plot_right + 1, axis_y + 1, kBlack);  // x axis
  for (std::size_t i = 0; i <= counts.size(); ++i) {  // x ticks at the bar edges
    const int x = std::min(kLeft + static_cast<int>(i) * kBarStep, plot_right);
    fill(image, x, axis_y + 1, x + 1, axis_y + 1 + kTickLength, kBlack);
  }
  return image;
}

fs::path write_class_summary(const ClassGrades& grades, const fs::path& dir) {
  const std::vector<std::string> tasks = grade_task_names(grades);
  const double maximum = points_maximum(grades);
  const std::string title =
      grades.rubric != nullptr && !grades.rubric->name.empty() ? grades.rubric->name : std::string("grades");
  std::string html = fmt::format("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                                 "<title>farm grade: {0}</title><style>{1}</style></head><body>\n"
                                 "<h1>farm grade: {0}</h1>\n<div class=\"counts\">{2} student{3} &middot; "
                                 "{4} task{5} &middot; {6} points at most</div>\n",
                                 markup_escape(title), kClassSummaryStyle, grades.students.size(),
                                 grades.students.size() == 1 ? "" : "s", tasks.size(), tasks.size() == 1 ? "" : "s",
                                 format_points(maximum));

  // Mean and median per task and of the totals.
  html += "<h2>Points</h2>\n<table>\n<tr><th>task</th><th>maximum</th><th>mean</th><th>median</th>"
          "<th>full points</th><th>graded</th></tr>\n";
  for (const std::string& task : tasks) {
    std::vector<double> points;
    int full = 0;
    double task_maximum = 0.0;
    bool hidden = false;
    for (const StudentGrade& s : grades.students) {
      if (const TaskGrade* t = find_task(s, task)) {
        points.push_back(t->points);
        task_maximum = t->max_points;
        hidden = t->visibility != Visibility::visible;
        if (round_points(t->points) >= round_points(t->max_points)) ++full;
      }
    }
    const Figures f = figures_of(points);
    html += fmt::format("<tr><td>{}{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td>"
                        "<td class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n",
                        markup_escape(task), hidden ? " <span class=\"hidden-note\">(hidden from students)</span>" : "",
                        format_points(task_maximum), format_points(f.mean), format_points(f.median), full,
                        points.size());
  }
  std::vector<double> totals;
  for (const StudentGrade& s : grades.students) totals.push_back(points_total(s));
  const Figures total = figures_of(totals);
  int full_total = 0;
  for (double t : totals)
    if (round_points(t) >= round_points(maximum)) ++full_total;
  html += fmt::format("<tr><td><b>total</b></td><td class=\"n\">{}</td><td class=\"n\"><b>{}</b></td>"
                      "<td class=\"n\"><b>{}</b></td><td class=\"n\">{}</td><td class=\"n\">{}</td></tr>\n</table>\n",
                      format_points(maximum), format_points(total.mean), format_points(total.median), full_total,
                      totals.size());

  // The distribution of totals: the picture, its axis labels and the counts as a table.
  const std::vector<int> counts = total_histogram(grades);
  const int max_count = std::max(1, *std::max_element(counts.begin(), counts.end()));
  const int step = tick_step(max_count);
  write_png_image(draw_histogram(counts, step), dir / kHistogramFile);
  html += fmt::format("<h2>Totals</h2>\n<div class=\"histogram\"><div>\n"
                      "<img src=\"{}\" width=\"{}\" height=\"{}\" alt=\"histogram of the totals\">\n"
                      "<div class=\"axis\">x: total points, each bar a tenth of {} (0 at the left, {} at the right); "
                      "y: students, a tick every {} (the tallest bar: {})</div></div>\n",
                      kHistogramFile, kHistogramWidth, kHistogramHeight, format_points(maximum),
                      format_points(maximum), step, max_count);
  html += "<table>\n<tr><th>total points</th><th>students</th></tr>\n";
  for (int i = 0; i < kHistogramBins; ++i) {
    const double lo = maximum * i / kHistogramBins, hi = maximum * (i + 1) / kHistogramBins;
    html += fmt::format("<tr><td>{} &ndash; {}{}</td><td class=\"n\">{}</td></tr>\n", format_points(lo),
                        format_points(hi), i + 1 == kHistogramBins ? " (inclusive)" : "",
                        counts[static_cast<std::size_t>(i)]);
  }
  html += "</table></div>\n";

  // Per task, who lost most.
  html += "<h2>Lost most</h2>\n";
  for (const std::string& task : tasks) {
    std::vector<std::pair<const StudentGrade*, const TaskGrade*>> lost;
    for (const StudentGrade& s : grades.students)
      if (const TaskGrade* t = find_task(s, task); t != nullptr && round_points(t->points) < round_points(t->max_points))
        lost.emplace_back(&s, t);
    std::stable_sort(lost.begin(), lost.end(), [](const auto& a, const auto& b) {
      if (a.second->points != b.second->points) return a.second->points < b.second->points;
      return a.first->student < b.first->student;
    });
    html += fmt::format("<h3>{}</h3>\n", markup_escape(task));
    if (lost.empty()) {
      html += "<p>Every student earned all points.</p>\n";
      continue;
    }
    if (lost.size() > static_cast<std::size_t>(kLostMostShown)) lost.resize(kLostMostShown);
    html += "<table>\n<tr><th>student</th><th>points</th><th>reason</th></tr>\n";
    for (const auto& [s, t] : lost)
      html += fmt::format("<tr><td>{}</td><td class=\"n\">{} / {}</td><td class=\"reason\">{}</td></tr>\n",
                          student_link(s->student), format_points(t->points), format_points(t->max_points),
                          markup_escape(t->reason));
    html += "</table>\n";
  }
  html += "</body></html>\n";
  const fs::path page = dir / "summary.html";
  write_text_atomically(page, html);
  return page;
}

}  // namespace farm
