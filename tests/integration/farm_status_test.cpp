// `farm status` lists a scheduler's jobs as an operator asks (issue #19): by state and by a name
// glob, the newest N, as aligned columns or JSON; and every command that names a job takes any
// unique start of its id, refusing one that names none or several.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/scheduler_client.h"

namespace farm {
namespace {

class FarmStatusTest : public test::FarmCliFixture {
 protected:
  void SetUp() override {
    scheduler_ = std::make_unique<test::SchedulerProcess>(dir_.path() / "data", std::vector<std::string>{});
    ASSERT_FALSE(scheduler_->address().empty()) << scheduler_->process().output();
    stub_ = test::scheduler_stub(scheduler_->address());
    ASSERT_TRUE(test::upload_assets(*stub_, test::cornell_assets()).ok());
  }

  // A job named `name`; the scheduler has no workers, so it stays queued.
  std::string submit(const std::string& name) {
    nlohmann::json job = nlohmann::json::parse(test::cornell_job_json("raster", 32, 32, 1));
    job["name"] = name;
    v1::Job submitted;
    const grpc::Status status = test::submit(*stub_, test::make_job_spec(job.dump(), test::cornell_assets()), submitted);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return submitted.job_id();
  }

  test::CommandResult status(const std::string& args) {
    return test::run_command(farm("status --scheduler " + scheduler_->address() + " " + args));
  }

  std::unique_ptr<test::SchedulerProcess> scheduler_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
};

TEST_F(FarmStatusTest, ListsByNameGlobStateAndLimitAsColumnsOrJson) {
  std::map<std::string, std::string> ids;
  for (const char* name : {"Cow turntable", "cow_still", "cornell", "cowl"}) ids[name] = submit(name);

  const test::CommandResult cows = status("--name 'cow*'");
  ASSERT_EQ(cows.exit_code, 0) << cows.output;
  EXPECT_NE(cows.output.find("PRI"), std::string::npos) << cows.output;
  EXPECT_NE(cows.output.find("DURATION"), std::string::npos) << cows.output;
  for (const char* name : {"Cow turntable", "cow_still", "cowl"}) {
    EXPECT_NE(cows.output.find(ids[name]), std::string::npos) << name << "\n" << cows.output;
  }
  EXPECT_EQ(cows.output.find(ids["cornell"]), std::string::npos) << cows.output;

  const test::CommandResult newest = status("--limit 2");
  ASSERT_EQ(newest.exit_code, 0) << newest.output;
  EXPECT_NE(newest.output.find(ids["cowl"]), std::string::npos) << newest.output;
  EXPECT_NE(newest.output.find(ids["cornell"]), std::string::npos) << newest.output;
  EXPECT_EQ(newest.output.find(ids["cow_still"]), std::string::npos) << newest.output;
  EXPECT_NE(newest.output.find("more match"), std::string::npos) << newest.output;

  // A job cancelled by the start of its id, then listed by state as JSON.
  const std::string& cowl = ids["cowl"];
  const test::CommandResult cancelled = test::run_command(
      farm("cancel --scheduler " + scheduler_->address() + " " + cowl.substr(0, 8)));
  ASSERT_EQ(cancelled.exit_code, 0) << cancelled.output;
  const test::CommandResult json = status("--state cancelled,failed --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  const nlohmann::json listed = nlohmann::json::parse(json.output);
  ASSERT_EQ(listed.size(), 1u) << json.output;
  EXPECT_EQ(listed[0]["job_id"], cowl);
  EXPECT_EQ(listed[0]["state"], "JOB_STATE_CANCELLED");
  EXPECT_EQ(listed[0]["name"], "cowl");
  const test::CommandResult queued = status("--state queued --json");
  EXPECT_EQ(nlohmann::json::parse(queued.output).size(), 3u) << queued.output;

  const test::CommandResult bad = status("--state finished");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("'finished' is not a job state"), std::string::npos) << bad.output;
}

TEST_F(FarmStatusTest, AJobIsNamedByAnyUniqueStartOfItsIdAndAnAmbiguousOneIsRefused) {
  // Seventeen ids share a first digit somewhere, by the pigeonhole.
  std::map<char, std::vector<std::string>> by_first;
  for (int i = 0; i < 17; ++i) {
    const std::string id = submit(fmt::format("job{}", i));
    by_first[id[0]].push_back(id);
  }
  std::string shared, unused;
  for (const char c : std::string("0123456789abcdef")) {
    if (by_first[c].size() >= 2 && shared.empty()) shared = std::string(1, c);
    if (by_first[c].empty() && unused.empty()) unused = std::string(1, c);
  }
  ASSERT_FALSE(shared.empty());

  const std::string one = by_first[shared[0]][0];
  const test::CommandResult found = status(one.substr(0, 12));
  ASSERT_EQ(found.exit_code, 0) << found.output;
  EXPECT_NE(found.output.find("job " + one), std::string::npos) << found.output;

  const test::CommandResult ambiguous = status(shared);
  EXPECT_EQ(ambiguous.exit_code, 2) << ambiguous.output;
  EXPECT_NE(ambiguous.output.find("is ambiguous"), std::string::npos) << ambiguous.output;
  // It names the first three that match (which three is the scheduler's order), "and more" past them.
  const std::vector<std::string>& sharing = by_first[shared[0]];
  std::size_t named = 0;
  for (const std::string& id : sharing) named += ambiguous.output.find(id) != std::string::npos;
  EXPECT_EQ(named, std::min<std::size_t>(sharing.size(), 3)) << ambiguous.output;
  EXPECT_EQ(ambiguous.output.find("and more") != std::string::npos, sharing.size() > 3) << ambiguous.output;

  if (!unused.empty()) {
    const test::CommandResult none = test::run_command(farm("watch --scheduler " + scheduler_->address() + " " + unused));
    EXPECT_NE(none.exit_code, 0) << none.output;
    EXPECT_NE(none.output.find("whose id starts with '" + unused + "'"), std::string::npos) << none.output;
  }
}

}  // namespace
}  // namespace farm
