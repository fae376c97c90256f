// `farm regress` end to end, as a CI pipeline runs it: a suite with a passing, a warning, a
// failing and a missing-reference test gives the right exit code, console lines, JUnit file (read
// back by junitparser), report and summary; --update writes exactly the failed and missing
// references; --filter skips; the same suite through a scheduler with two workers gives the same
// verdicts; bad suites exit 2 naming the JSON path.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string jobs_dir() { return std::string(FARM_SOURCE_DIR) + "/jobs"; }

class FarmRegressTest : public ::testing::Test {
 protected:
  void SetUp() override {
    suite_ = dir_.write("suite/suite.json", fmt::format(R"({{
  "version": 1, "name": "demo", "asset_root": "{0}",
  "compare": {{ "metric": "threshold", "fail": 0.05, "fail_percent": 1 }},
  "tests": [
    {{ "name": "cornell-pass", "job": "{0}/cornell.json", "render": {{ "width": 48, "height": 48 }},
      "compare": {{ "metric": "exact" }} }},
    {{ "name": "cornell-warn", "job": "{0}/cornell.json", "render": {{ "width": 48, "height": 48 }},
      "compare": {{ "fail_percent": 50, "warn": 0.001, "warn_percent": 0 }} }},
    {{ "name": "whitted-fail", "job": "{0}/whitted.json", "render": {{ "width": 48, "height": 36 }} }},
    {{ "name": "torus-missing", "job": "{0}/torus.json", "render": {{ "width": 48, "height": 36 }} }}
  ] }})", jobs_dir()));
    refs_ = dir_ / "suite/refs";
    // The references: the same render (pass), 1 spp instead of 4 (warn: edges differ), the
    // whitted scene rasterised (fail); none for the torus.
    render("cornell.json", "--width 48 --height 48", refs_ / "cornell-pass.exr");
    render("cornell.json", "--width 48 --height 48 --spp 1", refs_ / "cornell-warn.exr");
    render("whitted.json", "--width 48 --height 36 --engine raster", refs_ / "whitted-fail.exr");
  }

  void render(const std::string& job, const std::string& flags, const fs::path& out) {
    const test::CommandResult r = test::run_command(test::farm_command(
        fmt::format("render {} {} --out {} --preview none --quiet", test::shell_quote(jobs_dir() + "/" + job), flags,
                    test::shell_quote(out.string()))));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }

  test::CommandResult regress(const std::string& flags) {
    return test::run_command(test::farm_command(fmt::format("regress {} {} 2>&1", test::shell_quote(suite_.string()), flags)));
  }

  // Each test's status in a report's summary.json.
  static std::map<std::string, std::string> statuses(const fs::path& report) {
    const nlohmann::json summary = nlohmann::json::parse(test::read_file(report / "summary.json"));
    std::map<std::string, std::string> out;
    for (const auto& t : summary["tests"]) out[t["name"].get<std::string>()] = t["status"].get<std::string>();
    return out;
  }

  test::TempDir dir_;
  fs::path suite_, refs_;
};

TEST_F(FarmRegressTest, VerdictsExitCodeConsoleJunitAndReportThenUpdateWritesExactlyFailedAndMissing) {
  const fs::path report = dir_ / "report", junit = dir_ / "junit.xml";
  const test::CommandResult run =
      regress(fmt::format("--report {} --junit {}", test::shell_quote(report.string()), test::shell_quote(junit.string())));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("PASS  cornell-pass exact\n"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("WARN  cornell-warn threshold: "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("FAIL  whitted-fail threshold: "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("FAIL  torus-missing threshold: no reference at"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("--update"), std::string::npos) << "a missing reference says how to create it";
  EXPECT_NE(run.output.find("2 passed, 2 failed, 1 with warnings\n"), std::string::npos) << run.output;

  // The JUnit file, as junitparser reads it.
  ASSERT_TRUE(fs::exists(FARM_TEST_PYTHON)) << "run deploy/install-deps.sh: it makes the test venv";
  const test::CommandResult parsed = test::run_command(fmt::format(
      "{} {} {}", test::shell_quote(FARM_TEST_PYTHON),
      test::shell_quote(std::string(FARM_SOURCE_DIR) + "/tests/python/junit_summary.py"), test::shell_quote(junit.string())));
  ASSERT_EQ(parsed.exit_code, 0) << parsed.output;
  const nlohmann::json j = nlohmann::json::parse(parsed.output);
  EXPECT_EQ(j["tests"], 4);
  EXPECT_EQ(j["failures"], 2);
  EXPECT_EQ(j["errors"], 0);
  EXPECT_EQ(j["cases"]["cornell-pass"], "passed");
  EXPECT_EQ(j["cases"]["cornell-warn"], "passed");
  EXPECT_EQ(j["cases"]["whitted-fail"], "failure");
  EXPECT_EQ(j["cases"]["torus-missing"], "failure");
  EXPECT_EQ(j["properties"]["whitted-fail"]["metric"], "threshold");
  EXPECT_EQ(j["properties"]["whitted-fail"]["threshold.fail"], "0.05");
  EXPECT_TRUE(j["properties"]["whitted-fail"].contains("would_pass.fail"));

  // The report: failures first, the images it shows, a summary with every test.
  const std::string html = test::read_file(report / "index.html");
  ASSERT_FALSE(html.empty());
  EXPECT_LT(html.find("id=\"whitted-fail\""), html.find("id=\"cornell-warn\""));
  EXPECT_LT(html.find("id=\"cornell-warn\""), html.find("id=\"cornell-pass\""));
  EXPECT_NE(html.find("images/whitted-fail.diff.png"), std::string::npos);
  for (const char* image : {"whitted-fail.diff.png", "whitted-fail.ref.png", "whitted-fail.new-display.png"})
    EXPECT_TRUE(fs::exists(report / "images" / image)) << image;
  EXPECT_EQ(statuses(report), (std::map<std::string, std::string>{{"cornell-pass", "PASS"},
                                                                 {"cornell-warn", "WARN"},
                                                                 {"whitted-fail", "FAIL"},
                                                                 {"torus-missing", "FAIL"}}));

  // --update: the failed and the missing reference are written, the others left byte for byte.
  const std::string pass_before = test::read_file(refs_ / "cornell-pass.exr"), warn_before = test::read_file(refs_ / "cornell-warn.exr");
  const test::CommandResult update = regress(fmt::format("--report {} --update", test::shell_quote(report.string())));
  EXPECT_EQ(update.exit_code, 0) << update.output;
  // Said as what happened (issue #32: FAIL lines and "0 passed, 3 failed" while it wrote them).
  EXPECT_NE(update.output.find("UPDATED whitted-fail threshold: reference written to " + (refs_ / "whitted-fail.exr").string() +
                               " (it was: "),
            std::string::npos)
      << update.output;
  EXPECT_NE(update.output.find("NEW   torus-missing threshold: reference written to " + (refs_ / "torus-missing.exr").string() + "\n"),
            std::string::npos)
      << update.output;
  EXPECT_EQ(update.output.find("FAIL"), std::string::npos) << update.output;
  EXPECT_NE(update.output.find("2 passed, 0 failed, 1 with warnings, 2 references written (1 new)\n"), std::string::npos)
      << update.output;
  EXPECT_EQ(test::read_file(refs_ / "cornell-pass.exr"), pass_before);
  EXPECT_EQ(test::read_file(refs_ / "cornell-warn.exr"), warn_before);
  EXPECT_EQ(test::read_file(refs_ / "whitted-fail.exr"), test::read_file(report / "images/whitted-fail.new.exr"));
  EXPECT_EQ(test::read_file(refs_ / "torus-missing.exr"), test::read_file(report / "images/torus-missing.new.exr"));
  const test::CommandResult again = regress(fmt::format("--report {}", test::shell_quote(report.string())));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("4 passed, 0 failed, 1 with warnings\n"), std::string::npos) << again.output;

  // --filter: only the matching tests run; the others are reported as skipped.
  const test::CommandResult filtered = regress(fmt::format("--report {} --filter 'cornell-*'", test::shell_quote(report.string())));
  EXPECT_EQ(filtered.exit_code, 0) << filtered.output;
  EXPECT_NE(filtered.output.find("2 passed, 0 failed, 1 with warnings, 2 skipped\n"), std::string::npos) << filtered.output;
  EXPECT_EQ(filtered.output.find("whitted-fail"), std::string::npos) << filtered.output;
}

TEST_F(FarmRegressTest, TheSameSuiteThroughASchedulerWithTwoWorkersGivesTheSameVerdicts) {
  const fs::path local = dir_ / "local", remote = dir_ / "remote";
  const test::CommandResult embedded = regress(fmt::format("--report {} --jobs 2", test::shell_quote(local.string())));
  EXPECT_EQ(embedded.exit_code, 1) << embedded.output;

  const test::LocalFarm loopback = test::start_local_farm(dir_.path(), 2);
  ASSERT_TRUE(loopback.problem.empty()) << loopback.problem;
  const test::CommandResult farm = regress(
      fmt::format("--report {} --scheduler {}", test::shell_quote(remote.string()), test::shell_quote(loopback.address())));
  EXPECT_EQ(farm.exit_code, 1) << farm.output;
  EXPECT_EQ(statuses(remote), statuses(local));
  EXPECT_EQ(statuses(remote).at("cornell-pass"), "PASS") << "the farm's EXR is bit-identical to the embedded one";
}

TEST(FarmRegressSuiteFile, BadSuitesExitTwoNamingTheJsonPath) {
  test::TempDir dir;
  const std::string jobs = jobs_dir();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "JOBS/cornell.json", "colour": 1}]})", "tests[0].colour: unknown key"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "nowhere.json"}]})", "tests[0].job: no job file at"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "JOBS/cornell.json", "reference": "../../elsewhere.exr"}]})",
       "tests[0].reference: '../../elsewhere.exr' lies outside the suite's folder"},
      {R"({"version": 1, "name": "s", "references": "/tmp", "tests": [{"name": "a", "job": "JOBS/cornell.json"}]})",
       "references: '/tmp' lies outside the suite's folder"},
      {R"({"version": 1, "name": "s", "compare": {"metric": "ssimm"}, "tests": [{"name": "a", "job": "JOBS/cornell.json"}]})",
       "compare.metric: unknown metric 'ssimm'"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "JOBS/cornell.json", "compare": {"fail_percent": 120}}]})",
       "tests[0].compare.fail_percent"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "JOBS/cornell.json"}, {"name": "a", "job": "JOBS/cornell.json"}]})",
       "tests[1].name: a second test named 'a'"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "../a", "job": "JOBS/cornell.json"}]})", "tests[0].name: a name of letters"},
      {R"({"version": 2, "name": "s", "tests": []})", "version"},
      {R"({"version": 1, "name": "s", "tests": [{"name": "a", "job": "JOBS/cornell.json", "render": {"spp": 0}}]})",
       "tests[0].render.spp"},
  };
  for (const auto& [text, message] : cases) {
    std::string suite = text;
    for (std::size_t at; (at = suite.find("JOBS")) != std::string::npos;) suite.replace(at, 4, jobs);
    const fs::path file = dir.write("bad/suite.json", suite);
    const test::CommandResult r =
        test::run_command(test::farm_command(fmt::format("regress {} 2>&1", test::shell_quote(file.string()))));
    EXPECT_EQ(r.exit_code, 2) << text << "\n" << r.output;
    EXPECT_NE(r.output.find(file.string() + ": " + message), std::string::npos) << text << "\n" << r.output;
  }
}

}  // namespace
}  // namespace farm
