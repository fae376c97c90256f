// A farm spread over seven hosts (issue #18), each a network namespace on one bridge
// (tests/support/network_lab.h): PostgreSQL on one, a scheduler on each of two, a worker on each
// of three, the client on the last. Two jobs, one submitted to each scheduler, survive one
// scheduler killed (-9) and one worker's link taken down and brought back mid-job, and end
// bit-identical to `farm render`. Everything talks over the lab's network only; the lab is
// removed when the test ends, however it ends. Needs root (CI runs as root): skipped otherwise.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <thread>

#include "renderer/image/exr_io.h"
#include "tests/support/background_process.h"
#include "tests/support/network_lab.h"
#include "tests/support/pixel_diff.h"
#include "tests/support/postgres_server.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string command_line(const std::vector<std::string>& argv) {
  std::string line;
  for (const std::string& a : argv) line += fmt::format("{}{}", line.empty() ? "" : " ", test::shell_quote(a));
  return line;
}

// The example Cornell box job (jobs/cornell_path.json and its model) copied to `dir`.
fs::path copy_cornell_job(const fs::path& dir) {
  const fs::path jobs = fs::path(FARM_SOURCE_DIR) / "jobs";
  fs::create_directories(dir / "assets");
  fs::copy_file(jobs / "cornell_path.json", dir / "job.json");
  for (const char* f : {"cornell_box.obj", "cornell_box.mtl"}) fs::copy_file(jobs / "assets" / f, dir / "assets" / f);
  return dir / "job.json";
}

class MultiHostFarmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "network namespaces need root (CI runs as root)";
  }

  // `farm ARGS` on `host`, to its end (at most `limit`).
  test::CommandResult farm_on(const std::string& host, std::vector<std::string> args, int limit = 300) {
    args.insert(args.begin(), FARM_BINARY);
    args.insert(args.begin(), {"timeout", std::to_string(limit)});
    return test::run_command(command_line(lab_->on(host, args)));
  }

  // `farm status ID` on the client: tiles done so far, nullopt when the scheduler did not answer.
  std::optional<int> tiles_done(const std::string& scheduler, const std::string& id) {
    const test::CommandResult r = farm_on("client", {"status", "--scheduler", scheduler, id}, 30);
    std::smatch m;
    static const std::regex kProgress(R"(: [a-z]+, (\d+)/\d+ )");
    if (r.exit_code != 0 || !std::regex_search(r.output, m, kProgress)) return std::nullopt;
    return std::stoi(m[1]);
  }

  std::unique_ptr<ChildProcess> start_on(const std::string& host, std::vector<std::string> args) {
    args.insert(args.begin(), FARM_BINARY);
    auto p = std::make_unique<ChildProcess>(lab_->on(host, args));
    if (p->wait_for_line("listening on", 60s)) return p;
    ADD_FAILURE() << host << " did not start: " << p->output();
    return nullptr;
  }

  test::TempDir dir_;
  // First built, last gone: every process on it is stopped before the namespaces are deleted.
  std::unique_ptr<test::NetworkLab> lab_;
};

TEST_F(MultiHostFarmTest, JobsSurviveASchedulerKilledAndAWorkerCutOffAndEndBitIdentical) {
  lab_ = std::make_unique<test::NetworkLab>(std::vector<std::string>{"db", "s1", "s2", "w1", "w2", "w3", "client"});
  ASSERT_TRUE(lab_->problem().empty()) << lab_->problem();
  test::PostgresServer db(60s, {lab_->on("db", {}), lab_->address("db")});
  ASSERT_TRUE(db.problem().empty()) << db.problem();

  // The schedulers share the data dir (one file system, as NFS would make it) and the store.
  const std::string s1 = lab_->address("s1") + ":50051", s2 = lab_->address("s2") + ":50051";
  std::map<std::string, std::unique_ptr<ChildProcess>> schedulers;
  for (const auto& [host, address] : {std::pair{"s1", s1}, std::pair{"s2", s2}}) {
    schedulers[host] = start_on(host, {"scheduler", "--listen", address, "--insecure", "--data-dir",
                                       (dir_ / "data").string(), "--store", db.url(), "--lease", "2"});
    ASSERT_TRUE(schedulers[host]);
  }
  std::map<std::string, std::unique_ptr<ChildProcess>> workers;
  for (const char* host : {"w1", "w2", "w3"}) {
    workers[host] = start_on(host, {"worker", "--listen", lab_->address(host) + ":0", "--insecure", "--threads", "1",
                                    "--cache-dir", (dir_ / host).string(), "--scheduler", s1 + "," + s2});
    ASSERT_TRUE(workers[host]);
    for (const std::string& s : {s1, s2}) {
      EXPECT_TRUE(workers[host]->wait_for_line("registered with the scheduler " + s, 60s)) << workers[host]->output();
    }
  }

  // Two jobs, one through each scheduler: 48 and 16 units of the path tracer, tens of seconds of
  // work for the three workers.
  const fs::path job = copy_cornell_job(dir_ / "job");
  const std::vector<std::vector<std::string>> settings{
      {"--width", "256", "--height", "192", "--spp", "1024", "--tile-size", "32"},
      {"--width", "128", "--height", "128", "--spp", "512", "--tile-size", "32"}};
  std::vector<std::string> ids;
  for (std::size_t i = 0; i < 2; ++i) {
    std::vector<std::string> args{"submit", "--scheduler", i == 0 ? s1 : s2, job.string()};
    args.insert(args.end(), settings[i].begin(), settings[i].end());
    const test::CommandResult submitted = farm_on("client", args, 60);
    ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(submitted.output, m, std::regex("(^|\n)([0-9a-f]{16})\n"))) << submitted.output;
    ids.push_back(m[2]);
  }

  // Mid-job: the first job's scheduler killed, then the second worker's cable pulled.
  std::optional<int> done;
  const auto give_up = std::chrono::steady_clock::now() + 120s;
  while (!(done = tiles_done(s1, ids[0])) || *done < 3) {
    ASSERT_LT(std::chrono::steady_clock::now(), give_up) << schedulers["s1"]->output();
    std::this_thread::sleep_for(200ms);
  }
  ASSERT_LT(*done, 48) << "the job ended before the scheduler was killed";
  schedulers["s1"]->send_signal(SIGKILL);
  ASSERT_TRUE(schedulers["s1"]->wait_exit(10s));
  ASSERT_TRUE(lab_->set_link("w2", false)) << lab_->problem();
  // Long enough for the surviving scheduler to miss the worker's heartbeats and give its units
  // to the others; the jobs end the same however long the cut lasts.
  EXPECT_TRUE(schedulers["s2"]->wait_for_line("no heartbeat for", 30s)) << schedulers["s2"]->output();
  ASSERT_TRUE(lab_->set_link("w2", true)) << lab_->problem();

  for (std::size_t i = 0; i < 2; ++i) {
    const test::CommandResult watched = farm_on("client", {"watch", "--scheduler", s2, ids[i]}, 600);
    EXPECT_EQ(watched.exit_code, 0) << watched.output << schedulers["s2"]->output();
    const fs::path got = dir_ / fmt::format("got{}", i);
    const test::CommandResult fetched = farm_on("client", {"fetch", "--scheduler", s2, ids[i], "-o", got.string()}, 120);
    ASSERT_EQ(fetched.exit_code, 0) << fetched.output;
    std::optional<fs::path> exr;
    for (const fs::directory_entry& e : fs::directory_iterator(got)) {
      if (e.path().extension() == ".exr") exr = e.path();
    }
    ASSERT_TRUE(exr) << fetched.output;
    const fs::path expected = dir_ / fmt::format("expected{}.exr", i);
    std::vector<std::string> render{"render", job.string(), "--quiet", "--preview", "none", "--out", expected.string()};
    render.insert(render.end(), settings[i].begin(), settings[i].end());
    const test::CommandResult rendered = farm_on("client", render, 600);
    ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
    EXPECT_EQ(test::differing_pixels(read_exr(*exr), read_exr(expected)), 0) << "job " << i;
  }
  // The cut-off worker came back and registered again.
  const auto registrations = [&] {
    const std::string said = workers["w2"]->output();
    int n = 0;
    for (auto at = said.find("registered with the scheduler " + s2); at != std::string::npos;
         at = said.find("registered with the scheduler " + s2, at + 1)) {
      ++n;
    }
    return n;
  };
  const auto until = std::chrono::steady_clock::now() + 60s;
  while (registrations() < 2 && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(200ms);
  EXPECT_GE(registrations(), 2) << workers["w2"]->output();
}

}  // namespace
}  // namespace farm
