#include "server/regress/html_report.h"

#include <fmt/format.h>

#include <algorithm>

#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/regress/regress_summary.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStyle = R"(
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em; color: #222; }
h1 { margin-bottom: 0.2em; } .counts { color: #555; margin-bottom: 1.5em; }
.test { border: 1px solid #ccc; border-radius: 6px; margin: 1em 0; padding: 0.8em 1em; }
.FAIL, .ERROR { border-left: 8px solid #c62828; } .WARN { border-left: 8px solid #ef8f00; }
.PASS { border-left: 8px solid #2e7d32; } .SKIP { border-left: 8px solid #999; color: #777; }
.status { font-weight: bold; margin-right: 0.6em; } .message { font-family: monospace; margin: 0.4em 0; }
table { border-collapse: collapse; margin: 0.4em 0; } td { padding: 1px 10px 1px 0; font-family: monospace; }
.images { display: flex; gap: 12px; flex-wrap: wrap; } figure { margin: 0; }
figure img { width: 320px; height: auto; image-rendering: pixelated; border: 1px solid #ddd; display: block; }
figcaption { color: #555; font-size: 12px; }
.swap { position: relative; } .swap .ref { position: absolute; top: 0; left: 0; opacity: 0; }
.swap:hover .ref { opacity: 1; }
)";

int severity(TestStatus s) {
  switch (s) {
    case TestStatus::error: return 0;
    case TestStatus::failed: return 1;
    case TestStatus::warned: return 2;
    case TestStatus::passed: return 3;
    case TestStatus::skipped: return 4;
  }
  return 5;
}

std::string image_src(const fs::path& image) { return markup_escape("images/" + image.filename().string()); }

std::string test_section(const TestOutcome& o) {
  const std::string status(to_string(o.status));
  std::string html = fmt::format("<div class=\"test {0}\" id=\"{1}\"><span class=\"status\">{0}</span><b>{1}</b> &middot; {2}\n",
                                 status, markup_escape(o.name), to_string(o.settings.metric));
  html += fmt::format("<div class=\"message\">{}</div>\n", markup_escape(o.message));
  if (o.reference_updated) html += fmt::format("<div>reference written: {}</div>\n", markup_escape(o.reference.string()));
  html += "<table>\n";
  for (const Figure& f : o.result.figures)
    html += fmt::format("<tr><td>{}</td><td>{}</td></tr>\n", markup_escape(f.name), format_figure(f.value));
  for (const ThresholdKey& key : threshold_keys())
    if (key.metric == o.settings.metric)
      html += fmt::format("<tr><td>threshold {}</td><td>{}</td></tr>\n", key.name, format_figure(o.settings.*key.field));
  if (!o.result.would_pass_key.empty())
    html += fmt::format("<tr><td>would pass with {}</td><td>{}</td></tr>\n", markup_escape(o.result.would_pass_key),
                        format_figure(o.result.would_pass_value));
  html += "</table>\n<div class=\"images\">\n";
  if (!o.reference_png.empty())
    html += fmt::format("<figure><img src=\"{}\" alt=\"reference\"><figcaption>reference</figcaption></figure>\n",
                        image_src(o.reference_png));
  if (!o.new_png.empty()) {
    const std::string swap = o.reference_png.empty()
                                 ? std::string()
                                 : fmt::format("<img class=\"ref\" src=\"{}\" alt=\"reference\">", image_src(o.reference_png));
    html += fmt::format("<figure><div class=\"swap\"><img class=\"new\" src=\"{}\" alt=\"new\">{}</div>"
                        "<figcaption>new{}</figcaption></figure>\n",
                        image_src(o.new_png), swap, swap.empty() ? "" : " (hover: reference)");
  }
  if (!o.difference_png.empty())
    html += fmt::format("<figure><img src=\"{}\" alt=\"difference\"><figcaption>difference</figcaption></figure>\n",
                        image_src(o.difference_png));
  html += "</div></div>\n";
  return html;
}

}  // namespace

void write_html_report(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes, const fs::path& dir) {
  std::vector<const TestOutcome*> order;
  for (const TestOutcome& o : outcomes) order.push_back(&o);
  std::stable_sort(order.begin(), order.end(),
                   [](const TestOutcome* a, const TestOutcome* b) { return severity(a->status) < severity(b->status); });
  const RegressCounts counts = count_outcomes(outcomes);
  std::string html = fmt::format("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n"
                                 "<title>farm regress: {0}</title><style>{1}</style></head><body>\n"
                                 "<h1>farm regress: {0}</h1>\n<div class=\"counts\">{2} &middot; {3}</div>\n",
                                 markup_escape(suite.name), kStyle, markup_escape(counts.line()),
                                 markup_escape(suite.file.string()));
  for (const TestOutcome* o : order) html += test_section(*o);
  html += "</body></html>\n";
  write_text_atomically(dir / "index.html", html);
  write_text_atomically(dir / "summary.json", summary_json(suite, outcomes).dump(2) + "\n");
}

}  // namespace farm
