// The `farm` command line's shared declarations: option groups declared once stay the same in
// every command that takes them, and what --help and --version print comes from the one place
// each value lives (the renderer's engine names and job limits, CMake's project version).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "renderer/job/job_limits.h"
#include "renderer/job/render_settings.h"
#include "tests/support/farm_cli_fixture.h"

namespace farm {
namespace {

using test::run_command;

class FarmCliOptionsTest : public test::FarmCliFixture {};

// An option's entry in CLI11's help: its line and the indented lines that continue it.
std::string help_entry(const std::string& help, const std::string& option) {
  std::istringstream lines(help);
  std::string line, entry;
  bool inside = false;
  while (std::getline(lines, line)) {
    const bool continues = line.rfind("    ", 0) == 0;
    if (inside && !continues) break;
    if (inside || line.rfind(fmt::format("  {} ", option), 0) == 0) {
      inside = true;
      entry += line + "\n";
    }
  }
  return entry;
}

std::string help_of(const std::string& command) {
  const auto r = run_command(test::farm_command(fmt::format("{} --help", command)));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.output;
}

TEST_F(FarmCliOptionsTest, RenderAndSubmitShareTheRenderOverrideOptions) {
  const std::string render = help_of("render"), submit = help_of("submit");
  for (const std::string option : {"--engine", "--width", "--height", "--spp", "--tile-size"}) {
    const std::string entry = help_entry(render, option);
    EXPECT_FALSE(entry.empty()) << option << " missing from farm render --help:\n" << render;
    EXPECT_EQ(entry, help_entry(submit, option)) << option;
  }
}

TEST_F(FarmCliOptionsTest, EngineChoicesAreTheRenderersEngineNames) {
  std::string choices = "{";
  for (std::string_view name : kEngineNames) choices += fmt::format("{},", name);
  choices.back() = '}';
  for (const std::string command : {"render", "submit"}) {
    const std::string entry = help_entry(help_of(command), "--engine");
    EXPECT_NE(entry.find(choices), std::string::npos) << command << ":\n" << entry;
  }
}

TEST_F(FarmCliOptionsTest, OverrideRangesAreTheJobsLimits) {
  const std::string render = help_of("render");
  const auto range = [](int min, int max) { return fmt::format("[{} - {}]", min, max); };
  EXPECT_NE(help_entry(render, "--width").find(range(1, kMaxImageSide)), std::string::npos) << render;
  EXPECT_NE(help_entry(render, "--height").find(range(1, kMaxImageSide)), std::string::npos) << render;
  EXPECT_NE(help_entry(render, "--spp").find(range(1, kMaxSpp)), std::string::npos) << render;
  EXPECT_NE(help_entry(render, "--tile-size").find(range(1, kMaxTileSize)), std::string::npos) << render;
  EXPECT_NE(help_entry(render, "--threads").find(range(0, kMaxThreads)), std::string::npos) << render;
}

TEST_F(FarmCliOptionsTest, VersionIsTheCMakeProjectVersion) {
  const auto r = run_command(farm("--version"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, fmt::format("farm {}\n", FARM_PROJECT_VERSION));
}

// libpq and the twenty libraries it needs are loaded when a PostgreSQL store is opened, not by
// every command's start-up (libpq_library.h); the FarmSchedulerOnPostgresTest tests load it.
// The dynamic loader's own log says what `farm` loaded: SQLite, which it links, must be in it.
TEST_F(FarmCliOptionsTest, StartingUpLoadsNoLibpq) {
  const auto r = run_command("LD_DEBUG=libs " + farm("--version"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("libsqlite3.so"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("libpq.so"), std::string::npos) << r.output;
}

TEST_F(FarmCliOptionsTest, EveryCommandExplainsItselfInHelp) {
  const std::string overview = help_of("");
  const std::vector<std::string> commands = {"render", "info",   "validate",    "bench raster", "bench rt",
                                             "bench path", "bench farm", "bench render", "worker", "scheduler", "submit",
                                             "status", "watch", "cancel", "fetch"};
  for (const std::string& command : commands) {
    const std::string first_word = command.substr(0, command.find(' '));
    EXPECT_NE(overview.find(fmt::format("\n  {} ", first_word)), std::string::npos) << first_word << ":\n" << overview;
    const std::string help = help_of(command);
    // The description first, then the usage line that names the command.
    EXPECT_EQ(help.rfind("Usage:", 0), std::string::npos) << command << ":\n" << help;
    EXPECT_NE(help.find(fmt::format(" {} [OPTIONS]", command)), std::string::npos) << command << ":\n" << help;
  }
}

TEST_F(FarmCliOptionsTest, UnknownEngineIsBadInput) {
  const auto r = run_command(farm("render " + test::shell_quote((test::kSource / "jobs/cornell.json").string()) +
                                  " --engine rayleigh"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--engine"), std::string::npos) << r.output;
}

// `--log-level` reaches the embedded farm's scheduler: at info its "queued" line shows, by
// default (warn) it does not; a bad level is a usage error that names the choices.
TEST_F(FarmCliOptionsTest, LogLevelChoosesWhatTheEmbeddedFarmLogs) {
  const std::string render = "render " + test::shell_quote((test::kSource / "jobs/cornell.json").string()) +
                             " --width 16 --height 16 --preview none --quiet --out " +
                             test::shell_quote((dir_ / "out.exr").string());
  const auto quiet = run_command(farm(render));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("queued"), std::string::npos) << quiet.output;
  const auto chatty = run_command(farm(render + " --log-level info"));
  ASSERT_EQ(chatty.exit_code, 0) << chatty.output;
  EXPECT_NE(chatty.output.find("[scheduler] [info] job "), std::string::npos) << chatty.output;
  EXPECT_NE(chatty.output.find("queued"), std::string::npos) << chatty.output;
  const auto bad = run_command(farm(render + " --log-level loud"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("loud"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("trace, debug, info, warn, error"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace farm
