#include "server/regress/junit_report.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <ctime>

#include "server/common/markup_escape.h"
#include "renderer/util/atomic_file.h"
#include "server/regress/regress_summary.h"

namespace farm {
namespace {

std::string figures_text(const TestOutcome& o) {
  std::string text;
  for (const Figure& f : o.result.figures) text += fmt::format("{} = {}\n", f.name, format_figure(f.value));
  if (!o.result.would_pass_key.empty()) {
    text += fmt::format("would pass with {} = {}\n", o.result.would_pass_key, format_figure(o.result.would_pass_value));
  }
  return text;
}

std::string testcase(const RegressSuite& suite, const TestOutcome& o) {
  std::string out = fmt::format("    <testcase name=\"{}\" classname=\"regress.{}\" time=\"{:.3f}\">\n", markup_escape(o.name),
                                markup_escape(suite.name), o.seconds);
  out += "      <properties>\n";
  out += fmt::format("        <property name=\"metric\" value=\"{}\"/>\n", to_string(o.settings.metric));
  for (const ThresholdKey& key : threshold_keys())
    if (key.metric == o.settings.metric)
      out += fmt::format("        <property name=\"threshold.{}\" value=\"{}\"/>\n", key.name, format_figure(o.settings.*key.field));
  for (const Figure& f : o.result.figures)
    out += fmt::format("        <property name=\"{}\" value=\"{}\"/>\n", markup_escape(f.name), format_figure(f.value));
  if (!o.result.would_pass_key.empty())
    out += fmt::format("        <property name=\"would_pass.{}\" value=\"{}\"/>\n", markup_escape(o.result.would_pass_key),
                       format_figure(o.result.would_pass_value));
  out += "      </properties>\n";
  const std::string type(to_string(o.settings.metric));
  switch (o.status) {
    case TestStatus::failed:
      out += fmt::format("      <failure message=\"{}\" type=\"{}\">{}</failure>\n", markup_escape(o.message), type,
                         markup_escape(figures_text(o)));
      break;
    case TestStatus::error:
      out += fmt::format("      <error message=\"{}\" type=\"render\"/>\n", markup_escape(o.message));
      break;
    case TestStatus::skipped:
      out += fmt::format("      <skipped message=\"{}\"/>\n", markup_escape(o.message));
      break;
    case TestStatus::passed:
    case TestStatus::warned: break;
  }
  std::string system_out = o.status == TestStatus::warned ? "WARN: " + o.message + "\n" : std::string();
  for (const std::filesystem::path* image : {&o.difference_png, &o.new_png, &o.reference_png})
    if (!image->empty()) system_out += fmt::format("[[ATTACHMENT|{}]]\n", std::filesystem::absolute(*image).string());
  if (o.reference_updated) system_out += fmt::format("reference written: {}\n", o.reference.string());
  if (!system_out.empty()) out += fmt::format("      <system-out>{}</system-out>\n", markup_escape(system_out));
  out += "    </testcase>\n";
  return out;
}

}  // namespace

void write_junit_report(const RegressSuite& suite, const std::vector<TestOutcome>& outcomes,
                        const std::filesystem::path& file) {
  const RegressCounts c = count_outcomes(outcomes);
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char timestamp[32];
  std::strftime(timestamp, sizeof timestamp, "%Y-%m-%dT%H:%M:%S", std::gmtime(&now));
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  const std::size_t tests = outcomes.size();
  xml += fmt::format("<testsuites name=\"farm regress\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3f}\">\n",
                     tests, c.failed, c.errors, c.skipped, c.seconds);
  xml += fmt::format("  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{:.3f}\" "
                     "timestamp=\"{}\" file=\"{}\">\n",
                     markup_escape(suite.name), tests, c.failed, c.errors, c.skipped, c.seconds, timestamp,
                     markup_escape(suite.file.string()));
  for (const TestOutcome& o : outcomes) xml += testcase(suite, o);
  xml += "  </testsuite>\n</testsuites>\n";
  write_text_atomically(file, xml);
}

}  // namespace farm
