// Dependencies and caps through the command line as a user types them (issue #36): `farm submit
// --after`, `farm status`, `farm limits`, `farm depend` (a cycle refused), `farm cancel` and `farm
// log`, on a real scheduler with a real worker. No timing in it: the job everything waits for
// needs a worker tag no worker has, so it never starts until it is cancelled.
#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "server/common/job_state.h"
#include "tests/support/eventually.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

TEST(FarmSchedulingCli, SubmitAfterLimitsDependAndCancelSayWhatWaitsForWhat) {
  test::TempDir dir;
  test::LocalFarm farm = test::start_local_farm(dir.path(), 1);
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  for (const auto& [path, file] : test::cornell_assets()) dir.write("job/" + path, test::read_file(file));
  const auto write_job = [&](const std::string& name, const nlohmann::json& requirements) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
    job["output"] = {{"image", (dir / (name + ".exr")).string()}, {"preview", ""}};
    if (!requirements.is_null()) job["requirements"] = requirements;
    return test::shell_quote(dir.write("job/" + name + ".json", job.dump()).string());
  };
  const std::string at = " --scheduler " + farm.address();
  const auto farm_run = [&](const std::string& args) { return test::run_command(test::farm_command(args + at)); };
  // The id `farm submit` prints on stdout: its line of 16 hex digits (stderr says the rest).
  const auto submitted_id = [](const std::string& text) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
      if (line.size() == 16 && line.find_first_not_of("0123456789abcdef") == std::string::npos) return line;
    }
    return std::string("no id in: ") + text;
  };

  const test::CommandResult z = farm_run("submit " + write_job("z", {{"tags", {"nowhere"}}}));
  ASSERT_EQ(z.exit_code, 0) << z.output;
  const std::string z_id = submitted_id(z.output);
  const test::CommandResult b = farm_run("submit " + write_job("b", nullptr) + " --after " + z_id.substr(0, 8) +
                                         " --max-workers 1");
  ASSERT_EQ(b.exit_code, 0) << b.output;
  const std::string b_id = submitted_id(b.output);
  EXPECT_NE(b.output.find("waiting: after " + z_id), std::string::npos) << b.output;

  test::CommandResult status = farm_run("status " + b_id);
  EXPECT_NE(status.output.find(": waiting, "), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("  waiting: after " + z_id), std::string::npos) << status.output;
  EXPECT_NE(status.output.find("  caps: 1 workers, any units in flight at once"), std::string::npos) << status.output;
  status = farm_run("status " + z_id);
  EXPECT_NE(status.output.find("  waited for by: " + b_id), std::string::npos) << status.output;

  const test::CommandResult limits = farm_run("limits " + b_id + " --max-units-in-flight 3");
  ASSERT_EQ(limits.exit_code, 0) << limits.output;
  EXPECT_NE(limits.output.find("max 1 worker, max 3 units in flight"), std::string::npos) << limits.output;
  const test::CommandResult nothing = farm_run("depend " + b_id);
  EXPECT_NE(nothing.exit_code, 0) << nothing.output;
  EXPECT_NE(nothing.output.find("name the jobs to wait for"), std::string::npos) << nothing.output;
  const test::CommandResult cycle = farm_run("depend " + z_id + " --after " + b_id);
  EXPECT_NE(cycle.exit_code, 0) << cycle.output;
  EXPECT_NE(cycle.output.find("cannot wait for " + b_id + ": that would be a cycle"), std::string::npos) << cycle.output;

  ASSERT_EQ(farm_run("cancel " + z_id).exit_code, 0);
  auto stub = test::scheduler_stub(farm.address());
  const std::optional<v1::Job> failed =
      test::wait_for_job(*stub, b_id, [](const v1::Job& j) { return is_final(j.state()); }, 60s);
  ASSERT_TRUE(failed);
  EXPECT_EQ(failed->state(), v1::JOB_STATE_FAILED);
  EXPECT_EQ(failed->failure_reason(), "dependency " + z_id + " was cancelled");
  // The log has it once the change is announced, just after the store has it.
  test::CommandResult log;
  EXPECT_TRUE(test::eventually([&] {
    log = farm_run("log " + b_id);
    return log.output.find("waiting -> failed") != std::string::npos;
  }));
  EXPECT_NE(log.output.find("max_units_in_flight none -> 3"), std::string::npos) << log.output;
  EXPECT_NE(log.output.find("waiting -> failed (0/1 units): dependency " + z_id + " was cancelled"), std::string::npos)
      << log.output;
}

}  // namespace
}  // namespace farm
