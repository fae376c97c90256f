#include "server/cli/regress_command.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "renderer/job/job_limits.h"
#include "server/cli/progress_bar.h"
#include "server/cli/scheduler_target.h"
#include "server/client/scheduler_client.h"
#include "server/regress/html_report.h"
#include "server/regress/junit_report.h"
#include "server/regress/regress_runner.h"
#include "server/regress/regress_summary.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct RegressCommandOptions {
  fs::path suite;
  std::vector<std::string> filters;
  std::optional<std::string> update;  // "failed" (the flag alone) or "all"
  int jobs = 1;
  int threads = 0;
  std::optional<std::string> scheduler;
  SchedulerConnectionFlags identity;  // --token-file, --tls-*: used with --scheduler
  std::optional<fs::path> junit;
  std::optional<fs::path> report;
};

// "PASS cow-raster exact", "FAIL cbox-path ztest: <summary>"; with --update, "NEW cow-raster
// exact: reference written to PATH" for a test that had none and "UPDATED ...: reference written
// to PATH (it was: <summary>)" for one whose reference was replaced: no FAIL for what was fixed.
std::string outcome_line(const TestOutcome& o) {
  if (o.reference_updated) {
    const bool was_passing = o.status == TestStatus::passed || o.status == TestStatus::warned;
    return fmt::format("{:<5} {} {}: reference written to {}{}", o.reference_missing ? "NEW" : "UPDATED", o.name,
                       to_string(o.settings.metric), o.reference.string(),
                       o.reference_missing || was_passing ? "" : fmt::format(" (it was: {})", o.message));
  }
  std::string line = fmt::format("{:<5} {} {}", to_string(o.status), o.name, to_string(o.settings.metric));
  if (o.status != TestStatus::passed && o.status != TestStatus::skipped) line += ": " + o.message;
  return line;
}

int run_regress_command(const RegressCommandOptions& o) {
  const RegressSuite suite = load_regress_suite(o.suite);
  RegressOptions options;
  options.filters = o.filters;
  options.update = !o.update ? ReferenceUpdate::none : (*o.update == "all" ? ReferenceUpdate::all : ReferenceUpdate::failed);
  options.jobs = o.jobs;
  options.threads = o.threads;
  options.scheduler = resolve_optional_scheduler(o.scheduler, o.identity);
  options.output_dir = o.report ? *o.report : fs::path("regress-report") / suite.name;

  ProgressBar bar(suite.name, ProgressBar::stderr_is_terminal());
  RegressEvents events;
  events.finished = [&](const TestOutcome& outcome) {
    bar.clear();
    fmt::print("{}\n", outcome_line(outcome));
    std::fflush(stdout);
  };
  events.progress = [&](std::size_t done, std::size_t total) { bar.update(done, total); };
  const std::vector<TestOutcome> outcomes = run_regress_suite(suite, options, events);

  write_html_report(suite, outcomes, options.output_dir);
  if (o.junit) write_junit_report(suite, outcomes, *o.junit);
  const RegressCounts counts = count_outcomes(outcomes);
  fmt::print("{}\n", counts.line());
  fmt::print("report: {}\n", (options.output_dir / "index.html").string());
  if (o.junit) fmt::print("junit: {}\n", o.junit->string());
  return counts.exit_code();
}

}  // namespace

void add_regress_command(CLI::App& app, CommandTable& commands) {
  auto o = std::make_shared<RegressCommandOptions>();
  CLI::App* regress = app.add_subcommand(
      "regress", "Render a regression suite and compare every image with its reference (jobs/regress/README.md)");
  regress->add_option("SUITE", o->suite, "The suite file (JSON)")->required();
  regress->add_option("--filter", o->filters, "Run only the tests whose name matches this glob (repeatable)");
  regress->add_option("--update", o->update,
                      "Write the new image as the reference of every failed or missing test (--update), or of every "
                      "test (--update all); each file written is named")
      ->expected(0, 1)
      ->default_str("failed")
      ->check(CLI::IsMember({"failed", "all"}));
  regress->add_option("--jobs", o->jobs, "Embedded farm: tests rendered at a time (default 1)")->check(CLI::Range(1, 64));
  regress->add_option("--threads", o->threads, "Embedded farm: render threads (default: all cores)")
      ->check(CLI::Range(0, kMaxThreads));
  regress->add_option("--scheduler", o->scheduler,
                      "Render on this scheduler instead (HOST:PORT, or $FARM_SCHEDULER when given empty): every job is "
                      "submitted up front and compared as it finishes");
  add_client_identity_options(*regress, o->identity);
  regress->add_option("--junit", o->junit, "Write JUnit XML here");
  regress->add_option("--report", o->report, "The HTML report's folder (default regress-report/<suite name>/)");
  regress->footer("Exit codes: 0 every test passed (warnings pass), 1 a test failed or could not be rendered, "
                  "2 a bad suite file (the message names the JSON path).");
  commands.add(regress, [o] { return run_regress_command(*o); });
}

}  // namespace farm
