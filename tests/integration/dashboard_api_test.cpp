// The scheduler's dashboard API (issue #19), read by a client that is not ours to trust it:
// `farm scheduler --http` with tokens, called over HTTP (cpp-httplib's client) the way a browser
// or a script does. The JSON parses (nlohmann) into what the RPCs return, the actions obey the
// same roles as gRPC, the event stream's events arrive in order, /metrics parses as Prometheus
// text with the figures of the farm, and a page from elsewhere cannot make a browser act.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "server/common/job_state.h"
#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using json = nlohmann::json;

constexpr auto kWait = 120s;
const std::string kAdmin = "admin-token-0123456789abcdef";
const std::string kAlice = "alice-token-0123456789abcdef";  // submit
const std::string kBob = "bob-token-0123456789abcdef01";    // submit
const std::string kReader = "reader-token-0123456789abcd";  // read

class DashboardApiTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path tokens = dir_.write(
        "tokens.txt", fmt::format("{} boss admin\n{} alice submit\n{} bob submit\n{} reader read\n", sha256_hex(kAdmin),
                                  sha256_hex(kAlice), sha256_hex(kBob), sha256_hex(kReader)));
    worker_ = std::make_unique<test::WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir_ / "w1").string()});
    ASSERT_FALSE(worker_->address().empty());
    scheduler_ = std::make_unique<test::SchedulerProcess>(
        dir_ / "data", std::vector<std::string>{"--tokens", tokens.string(), "--http", "127.0.0.1:0", "--worker",
                                                worker_->address(), "--batch-ms", "0"});
    ASSERT_FALSE(scheduler_->address().empty()) << scheduler_->process().output();
    const std::string url = scheduler_->dashboard_url();
    ASSERT_FALSE(url.empty()) << scheduler_->process().output();
    address_ = url.substr(std::string("http://").size());
  }

  // A job submitted over gRPC as `token`'s holder.
  std::string submit(const std::string& token, const std::string& name, int size = 32,
                     const std::string& engine = "whitted", int spp = 1, const std::string& image = "") {
    auto stub = test::scheduler_stub(scheduler_->address(), ClientIdentity{token, false, {}});
    EXPECT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
    json job = json::parse(test::cornell_job_json(engine, size, size, spp));
    job["name"] = name;
    job["render"]["tile_size"] = 16;
    if (!image.empty()) job["output"]["image"] = image;
    v1::Job submitted;
    const grpc::Status status =
        test::submit(*stub, test::make_job_spec(job.dump(), test::cornell_assets(), "cornell.json"), submitted);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return submitted.job_id();
  }

  httplib::Client client() const {
    httplib::Client c("http://" + address_);
    c.set_read_timeout(30, 0);
    return c;
  }

  static httplib::Headers bearer(const std::string& token) { return {{"Authorization", "Bearer " + token}}; }

  json get(const std::string& path, const std::string& token, int want = 200) {
    httplib::Client c = client();
    const httplib::Result r = c.Get(path, bearer(token));
    EXPECT_TRUE(r) << path;
    if (!r) return {};
    EXPECT_EQ(r->status, want) << path << ": " << r->body;
    return json::parse(r->body);
  }

  httplib::Result post(const std::string& path, const httplib::Headers& headers, const std::string& body = "{}",
                       const char* type = "application/json") {
    httplib::Client c = client();
    return c.Post(path, headers, body, type);
  }

  json wait_final(const std::string& id) {
    const auto until = std::chrono::steady_clock::now() + kWait;
    json job;
    while (std::chrono::steady_clock::now() < until) {
      job = get("/api/v1/jobs/" + id, kAdmin);
      if (job["state"] == "JOB_STATE_SUCCEEDED" || job["state"] == "JOB_STATE_FAILED" ||
          job["state"] == "JOB_STATE_CANCELLED") {
        return job;
      }
      std::this_thread::sleep_for(50ms);
    }
    ADD_FAILURE() << "job " << id << " did not end";
    return job;
  }

  test::TempDir dir_;
  std::unique_ptr<test::WorkerProcess> worker_;
  std::unique_ptr<test::SchedulerProcess> scheduler_;
  std::string address_;
};

TEST_F(DashboardApiTest, JobsLogAndActionsMirrorTheRpcsWithTheirRoles) {
  const std::string mine = submit(kAlice, "alice-cow");
  const json done = wait_final(mine);
  EXPECT_EQ(done["state"], "JOB_STATE_SUCCEEDED");
  EXPECT_EQ(done["owner"], "alice");
  EXPECT_EQ(done["tiles_done"], done["tiles_total"]);

  // Who may see and do what: as over gRPC.
  get("/api/v1/jobs", "", 401);
  get("/api/v1/jobs", "not-a-token-0123456789abcdef", 401);
  EXPECT_EQ(get("/api/v1/jobs?name=ALICE*", kAlice)["jobs"].size(), 1u);
  EXPECT_EQ(get("/api/v1/jobs", kBob)["jobs"].size(), 0u);  // a submitter lists its own jobs
  EXPECT_EQ(get("/api/v1/jobs?state=succeeded", kReader)["jobs"][0]["job_id"], mine);
  get("/api/v1/jobs/" + mine, kBob, 403);
  get("/api/v1/jobs?state=sleeping", kAdmin, 400);
  const json log = get("/api/v1/jobs/" + mine + "/log", kReader);
  ASSERT_GE(log["entries"].size(), 3u) << log.dump();
  EXPECT_EQ(log["entries"][0]["number"], 1);
  EXPECT_EQ(log["entries"][0]["event"]["state_changed"]["to"], "JOB_STATE_QUEUED");
  EXPECT_EQ(log["entries"].back()["event"]["state_changed"]["to"], "JOB_STATE_SUCCEEDED");
  // Its start is logged once, between its submission and its first merge.
  std::vector<std::size_t> starts;
  std::size_t first_merge = log["entries"].size();
  for (std::size_t i = 0; i < log["entries"].size(); ++i) {
    const json& event = log["entries"][i]["event"];
    if (event.contains("state_changed") && event["state_changed"]["to"] == "JOB_STATE_RUNNING") {
      EXPECT_EQ(event["state_changed"]["from"], "JOB_STATE_QUEUED");
      starts.push_back(i);
    }
    if (event.contains("frame_finished")) first_merge = std::min(first_merge, i);
  }
  ASSERT_EQ(starts.size(), 1u) << log.dump();
  EXPECT_EQ(starts[0], 1u) << log.dump();
  EXPECT_LT(starts[0], first_merge) << log.dump();

  httplib::Result r = post("/api/v1/jobs/" + mine + "/delete", bearer(kBob));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403) << r->body;  // not bob's
  r = post("/api/v1/jobs/" + mine + "/priority", bearer(kAlice), R"({"priority": 7})");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["priority"], 7);
  r = post("/api/v1/jobs/" + mine + "/priority", bearer(kAlice), R"({"priority": 1000})");
  EXPECT_EQ(r->status, 403) << r->body;  // above --max-priority: admin only
  r = post("/api/v1/jobs/" + mine + "/retry", bearer(kAlice));
  EXPECT_EQ(r->status, 409) << r->body;  // it succeeded
  EXPECT_EQ(json::parse(r->body)["error"], "FAILED_PRECONDITION");

  // The files: its preview and EXR, as GetResult serves them.
  httplib::Client c = client();
  const httplib::Result png = c.Get("/api/v1/jobs/" + mine + "/file?kind=preview&frame=0", bearer(kReader));
  ASSERT_TRUE(png);
  EXPECT_EQ(png->status, 200);
  EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(png->body.substr(1, 3), "PNG");
  const httplib::Result live = c.Get("/api/v1/jobs/" + mine + "/live?frame=0", bearer(kReader));
  ASSERT_TRUE(live);
  EXPECT_EQ(live->body, png->body);  // a merged frame's live image is its preview

  r = post("/api/v1/jobs/" + mine + "/delete", bearer(kAlice));
  EXPECT_EQ(r->status, 200) << r->body;
  get("/api/v1/jobs/" + mine, kAdmin, 404);

  // A download is named after the submitter's output name: a quote or a line break in it becomes
  // '_', so that the header is well formed (httplib drops one with a line break, name and all).
  const std::string odd = submit(kAlice, "odd-name", 16, "whitted", 1, "out/we\"ird\r\nX-Injected: yes.exr");
  ASSERT_EQ(wait_final(odd)["state"], "JOB_STATE_SUCCEEDED");
  const httplib::Result exr = c.Get("/api/v1/jobs/" + odd + "/file?kind=exr", bearer(kAlice));
  ASSERT_TRUE(exr);
  EXPECT_EQ(exr->status, 200) << exr->body;
  EXPECT_EQ(exr->get_header_value("Content-Disposition"), "attachment; filename=\"we_ird__X-Injected__yes.exr\"");
  EXPECT_FALSE(exr->has_header("X-Injected"));
  EXPECT_EQ(exr->body.substr(0, 4), std::string("\x76\x2f\x31\x01", 4));  // OpenEXR's magic number

  // Who cancelled is said in the log (issue #32): the admin's cancel of Alice's long job.
  const std::string long_job = submit(kAlice, "long", 128, "path", 4096);
  r = post("/api/v1/jobs/" + long_job + "/cancel", bearer(kAdmin));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  const json cancel_log = get("/api/v1/jobs/" + long_job + "/log", kReader);
  bool said = false;
  for (const json& entry : cancel_log["entries"]) {
    const json& change = entry["event"]["state_changed"];
    if (change.is_object() && change["to"] == "JOB_STATE_CANCELLED") said = change["by"] == "boss";
  }
  EXPECT_TRUE(said) << cancel_log.dump();
}

TEST_F(DashboardApiTest, ALoginSessionActsAndAPageElsewhereCannot) {
  // 256 path-traced units on one thread: still running when it is cancelled.
  const std::string id = submit(kAdmin, "to-cancel", 256, "path", 64);
  httplib::Result r = post("/api/v1/login", {}, fmt::format(R"({{"token": "{}"}})", kAlice));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200) << r->body;
  const std::string cookie = r->get_header_value("Set-Cookie");
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos) << cookie;
  EXPECT_NE(cookie.find("SameSite=Strict"), std::string::npos) << cookie;
  EXPECT_EQ(cookie.find(kAlice), std::string::npos) << "the token itself is never a cookie";
  const std::string session = cookie.substr(0, cookie.find(';'));
  get("/api/v1/whoami", "", 401);
  httplib::Client c = client();
  const httplib::Result who = c.Get("/api/v1/whoami", {{"Cookie", session}});
  ASSERT_TRUE(who);
  EXPECT_EQ(json::parse(who->body)["name"], "alice");
  // alice may not cancel the admin's job; the admin's session may.
  r = post("/api/v1/jobs/" + id + "/cancel", {{"Cookie", session}});
  EXPECT_EQ(r->status, 403) << r->body;
  r = post("/api/v1/login", {}, R"({"token": "wrong-token-0123456789abcdef"})");
  EXPECT_EQ(r->status, 401) << r->body;
  r = post("/api/v1/login", {}, fmt::format(R"({{"token": "{}"}})", kAdmin));
  const std::string admin = r->get_header_value("Set-Cookie").substr(0, r->get_header_value("Set-Cookie").find(';'));
  // A form another site posts, or a JSON POST that says it comes from elsewhere: refused.
  r = post("/api/v1/jobs/" + id + "/cancel", {{"Cookie", admin}}, "x=1", "application/x-www-form-urlencoded");
  EXPECT_EQ(r->status, 403) << r->body;
  r = post("/api/v1/jobs/" + id + "/cancel", {{"Cookie", admin}, {"Origin", "http://evil.example"}});
  EXPECT_EQ(r->status, 403) << r->body;
  r = post("/api/v1/jobs/" + id + "/cancel", {{"Cookie", admin}, {"Origin", "http://" + address_}});
  EXPECT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["state"], "JOB_STATE_CANCELLED");
  r = post("/api/v1/logout", {{"Cookie", admin}});
  EXPECT_EQ(r->status, 200);
  const httplib::Result gone = c.Get("/api/v1/whoami", {{"Cookie", admin}});
  EXPECT_EQ(gone->status, 401);
  // The pages are served, locked to this origin.
  const httplib::Result page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<table id=\"jobs\">"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("default-src 'self'"), std::string::npos);
  EXPECT_EQ(c.Get("/../jobs.db")->status, 404);
}

TEST_F(DashboardApiTest, EventsArriveInOrderAndMetricsParseWithTheFarmsFigures) {
  // The stream first, then the job: every event of it comes, numbered, in the store's order.
  std::vector<json> events;
  std::vector<long> ids;
  std::string buffer;
  std::atomic<bool> subscribed{false}, ended{false};
  std::thread reader([&] {
    httplib::Client c = client();
    c.set_read_timeout(kWait.count(), 0);
    c.Get("/api/v1/events", bearer(kReader), [&](const char* data, std::size_t n) {
      subscribed = true;
      buffer.append(data, n);
      for (std::size_t end; (end = buffer.find("\n\n")) != std::string::npos; buffer.erase(0, end + 2)) {
        const std::string block = buffer.substr(0, end);
        std::smatch m;
        static const std::regex line(R"(id: (\d+)\nevent: job\ndata: (.*))");
        if (!std::regex_match(block, m, line)) continue;
        ids.push_back(std::stol(m[1]));
        events.push_back(json::parse(m[2].str()));
        const json& e = events.back();
        if (e.contains("state_changed") && e["state_changed"]["to"] == "JOB_STATE_SUCCEEDED") {
          ended = true;
          return false;
        }
      }
      return true;
    });
  });
  const auto until = std::chrono::steady_clock::now() + kWait;
  while (!subscribed && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(10ms);
  const std::string id = submit(kAdmin, "streamed", 64);
  reader.join();
  ASSERT_TRUE(ended) << events.size() << " events";
  ASSERT_GE(events.size(), 3u);
  EXPECT_EQ(events.front()["state_changed"]["from"], "JOB_STATE_UNSPECIFIED");  // submitted
  long last_id = 0;
  unsigned last_done = 0;
  int finished = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    EXPECT_GT(ids[i], last_id);
    last_id = ids[i];
    EXPECT_EQ(events[i]["job"]["job_id"], id);
    const unsigned done = events[i]["job"]["tiles_done"];
    EXPECT_GE(done, last_done) << i;  // progress never goes back
    last_done = done;
    finished += events[i].contains("tile_finished") ? 1 : 0;
  }
  EXPECT_EQ(last_done, 16u);
  EXPECT_GE(finished, 1);

  // /metrics, read by Prometheus's own parser (tests/python/prometheus_metrics.py), which also
  // holds the histogram to its rules.
  httplib::Client c = client();
  EXPECT_EQ(c.Get("/metrics")->status, 401);
  const httplib::Result m = c.Get("/metrics", bearer(kReader));
  ASSERT_TRUE(m);
  ASSERT_EQ(m->status, 200) << m->body;
  const fs::path text = dir_.write("metrics.txt", m->body);
  const test::CommandResult parsed = test::run_command(
      fmt::format("/usr/bin/python3 {} < {}", test::shell_quote((fs::path(FARM_SOURCE_DIR) / "tests/python/prometheus_metrics.py").string()),
                  test::shell_quote(text.string())));
  ASSERT_EQ(parsed.exit_code, 0) << parsed.output << "\n" << m->body;
  const json metrics = json::parse(parsed.output);
  const json& families = metrics["families"];
  EXPECT_EQ(families["farm_jobs"], "gauge");
  EXPECT_EQ(families["farm_units_done"], "counter");  // the parser names a counter without _total
  EXPECT_EQ(families["farm_unit_latency_seconds"], "histogram");
  const std::map<std::string, double> samples = metrics["samples"].get<std::map<std::string, double>>();
  const auto sample = [&](const std::string& key) {
    const auto it = samples.find(key);
    EXPECT_NE(it, samples.end()) << key << " missing from\n" << m->body;
    return it == samples.end() ? -1.0 : it->second;
  };
  EXPECT_EQ(sample("farm_jobs{state=\"succeeded\"}"), 1);
  EXPECT_EQ(sample("farm_jobs{state=\"running\"}"), 0);
  EXPECT_EQ(sample("farm_workers{state=\"up\"}"), 1);
  EXPECT_EQ(sample("farm_units_done_total"), 16);
  EXPECT_EQ(sample("farm_queue_depth"), 0);
  EXPECT_GT(sample("farm_units_per_second"), 0);
  EXPECT_EQ(sample("farm_unit_latency_seconds_bucket{le=\"+Inf\"}"), sample("farm_unit_latency_seconds_count"));
  EXPECT_GE(sample("farm_unit_latency_seconds_count"), 1);
}

TEST(DashboardListenTest, BeyondLoopbackWithoutTokensTheDashboardIsRefused) {
  test::TempDir dir;
  const test::CommandResult r = test::run_command(
      test::farm_command("scheduler --listen 127.0.0.1:0 --http 0.0.0.0:0 --data-dir " + (dir / "data").string()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--tokens"), std::string::npos) << r.output;
}

// DNS rebinding (issue #32): a page on attacker.example whose name is made to resolve to
// 127.0.0.1 talks to a token-less dashboard as its own origin, Host and Origin alike
// attacker.example. The dashboard answers only to the names it serves.
TEST(DashboardListenTest, ARequestForAnotherHostNameIsRefusedAndTheNamesItServesAreAnswered) {
  test::TempDir dir;
  auto worker = std::make_unique<test::WorkerProcess>(
      std::vector<std::string>{"--threads", "1", "--cache-dir", (dir / "w1").string()});
  ASSERT_FALSE(worker->address().empty());
  test::SchedulerProcess scheduler(dir / "data", {"--http", "127.0.0.1:0", "--http-host", "Farm.Example.org",
                                                  "--worker", worker->address()});
  const std::string url = scheduler.dashboard_url();
  ASSERT_FALSE(url.empty()) << scheduler.process().output();
  const std::string address = url.substr(std::string("http://").size());
  const std::string port = address.substr(address.rfind(':') + 1);

  auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  v1::Job job;
  ASSERT_TRUE(test::submit(*stub,
                           test::make_job_spec(test::cornell_job_json("raster", 16, 16, 1), test::cornell_assets(),
                                               "cornell.json"),
                           job)
                  .ok());
  ASSERT_TRUE(test::wait_for_job(*stub, job.job_id(), [](const v1::Job& j) { return is_final(j.state()); }, kWait));

  httplib::Client c("http://" + address);
  c.set_read_timeout(30, 0);
  const httplib::Headers rebound{{"Host", "attacker.example:" + port}, {"Origin", "http://attacker.example:" + port}};
  httplib::Result r = c.Get("/api/v1/jobs", rebound);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 421) << r->body;
  EXPECT_EQ(r->body.find(job.job_id()), std::string::npos) << r->body;
  EXPECT_NE(r->body.find("--http-host"), std::string::npos) << r->body;
  r = c.Post("/api/v1/jobs/" + job.job_id() + "/delete", rebound, "{}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 421) << r->body;
  r = c.Get("/", rebound);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 421);
  // A name under an allowed one is not allowed, nor one that only starts like it.
  for (const char* host : {"sub.farm.example.org", "farm.example.org.attacker.example", ""}) {
    r = c.Get("/api/v1/jobs", {{"Host", host}});
    ASSERT_TRUE(r);
    EXPECT_NE(r->status, 200) << host;
  }

  // The job is still there, and the names the dashboard serves get it.
  for (const std::string& host : {"127.0.0.1:" + port, "localhost:" + port, "farm.example.org:" + port,
                                 std::string("FARM.EXAMPLE.ORG"), "[::1]:" + port}) {
    r = c.Get("/api/v1/jobs", {{"Host", host}});
    ASSERT_TRUE(r) << host;
    EXPECT_EQ(r->status, 200) << host << ": " << r->body;
    EXPECT_NE(r->body.find(job.job_id()), std::string::npos) << host;
  }
}

}  // namespace
}  // namespace farm
