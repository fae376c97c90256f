// Who may call what (issue #15): bearer tokens with roles on a real `farm scheduler` and
// `farm worker`, every Scheduler RPC against every kind of caller; the listen policy; the CLI's
// --token-file and FARM_TOKEN.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/common/job_state.h"
#include "server/common/sha256.h"
#include "server/common/token_table.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Code = grpc::StatusCode;

constexpr auto kCall = 30s;

// The callers of the table: one token per role, two submitters, and two without a valid token.
const std::map<std::string, std::string> kTokens = {
    {"alice", "alice-token-0123456789abcdef"},   // submit
    {"bob", "bob-token-0123456789abcdef01"},     // submit
    {"reader", "reader-token-0123456789abcd"},   // read
    {"boss", "boss-token-0123456789abcdef01"},   // admin
    {"w1", "worker-token-0123456789abcdef"},     // worker
    {"sched", "sched-token-0123456789abcdef"},   // scheduler
};

std::string tokens_file_text() {
  const std::map<std::string, std::string> roles = {{"alice", "submit"}, {"bob", "submit"},
                                                    {"reader", "read"},  {"boss", "admin"},
                                                    {"w1", "worker"},    {"sched", "scheduler"}};
  std::string text = "# test tokens\n";
  for (const auto& [name, token] : kTokens) text += sha256_hex(token) + "  " + name + "  " + roles.at(name) + "\n";
  return text;
}

ClientIdentity as(const std::string& caller) {
  ClientIdentity id;
  if (caller == "bad") id.token = "not-a-listed-token-0000";
  else if (caller != "none") id.token = kTokens.at(caller);
  return id;
}

void set_deadline(grpc::ClientContext& c) { c.set_deadline(std::chrono::system_clock::now() + kCall); }

class FarmAccessTest : public ::testing::Test {
 protected:
  test::TempDir dir;
  fs::path tokens = dir.write("tokens.txt", tokens_file_text());
};

// Every RPC of farm.v1.Scheduler, called by every kind of caller, against what its roles allow.
TEST_F(FarmAccessTest, EachRoleAgainstEachSchedulerRpc) {
  test::SchedulerProcess scheduler(dir / "data", {"--tokens", tokens.string()});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const fs::path w1_token = dir.write("w1.token", kTokens.at("w1") + "\n");
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir / "w1").string(), "--scheduler",
                              scheduler.address(), "--token-file", w1_token.string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  ASSERT_TRUE(worker.process().wait_for_line("registered with the scheduler", 20s)) << worker.process().output();

  // Alice's job: the worker, with an empty cache, fetched its assets with the worker role while
  // the call that needed them was in flight.
  auto alice = test::scheduler_stub(scheduler.address(), as("alice"));
  const v1::JobSpec spec = test::cornell_job_spec("raster", 24, 16, 1);
  ASSERT_TRUE(test::upload_assets(*alice, test::cornell_assets()).ok());
  v1::Job job;
  ASSERT_TRUE(test::submit(*alice, spec, job).ok());
  EXPECT_EQ(job.owner(), "alice");
  const auto done = test::wait_for_job(*alice, job.job_id(), [](const v1::Job& j) { return is_final(j.state()); }, 60s);
  ASSERT_TRUE(done && done->state() == v1::JOB_STATE_SUCCEEDED) << (done ? done->failure_reason() : "timeout");
  const std::string asset_sha = spec.assets(0).sha256();

  using Call = std::function<grpc::Status(v1::Scheduler::Stub&)>;
  auto register_at = [](v1::Scheduler::Stub& s, const std::string& address) {
    grpc::ClientContext c;
    set_deadline(c);
    v1::RegisterWorkerRequest r;
    r.set_address(address);
    r.set_threads(1);
    v1::RegisterWorkerResponse out;
    return s.RegisterWorker(&c, r, &out);
  };
  int next_port = 9000;
  const std::map<std::string, Call> rpcs = {
      {"GetJob", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::GetJobRequest r; r.set_job_id(job.job_id()); v1::Job out;
         return s.GetJob(&c, r, &out); }},
      {"ListJobs", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::ListJobsRequest r; v1::ListJobsResponse out;
         return s.ListJobs(&c, r, &out); }},
      {"WatchJob", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::WatchJobRequest r; r.set_job_id(job.job_id());
         auto reader = s.WatchJob(&c, r);
         v1::JobEvent e;
         while (reader->Read(&e)) {}
         return reader->Finish(); }},
      {"GetResult", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::GetResultRequest r; r.set_job_id(job.job_id()); r.set_kind(v1::RESULT_KIND_PREVIEW);
         auto reader = s.GetResult(&c, r);
         v1::FileChunk chunk;
         while (reader->Read(&chunk)) {}
         return reader->Finish(); }},
      {"CancelJob", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::CancelJobRequest r; r.set_job_id(job.job_id()); v1::CancelJobResponse out;
         return s.CancelJob(&c, r, &out); }},
      {"HasAssets", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::HasAssetsRequest r; r.add_sha256(asset_sha); v1::HasAssetsResponse out;
         return s.HasAssets(&c, r, &out); }},
      {"UploadAsset", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::UploadAssetResponse out;
         auto writer = s.UploadAsset(&c, &out);
         v1::UploadAssetRequest header;
         header.mutable_header()->set_sha256(sha256_hex("hello"));
         header.mutable_header()->set_size(5);
         v1::UploadAssetRequest data;
         data.set_data("hello");
         if (writer->Write(header)) writer->Write(data);
         writer->WritesDone();
         return writer->Finish(); }},
      {"SubmitJob", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::SubmitJobRequest r; *r.mutable_job() = spec; r.set_priority(5); v1::SubmitJobResponse out;
         return s.SubmitJob(&c, r, &out); }},
      {"SubmitJob priority 1000", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::SubmitJobRequest r; *r.mutable_job() = spec; r.set_priority(1000); v1::SubmitJobResponse out;
         return s.SubmitJob(&c, r, &out); }},
      {"GetAsset", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::GetAssetRequest r; r.set_sha256(asset_sha);
         auto reader = s.GetAsset(&c, r);
         v1::AssetChunk chunk;
         while (reader->Read(&chunk)) {}
         return reader->Finish(); }},
      {"RegisterWorker", [&](v1::Scheduler::Stub& s) {
         // Addresses where nothing listens: those workers stay down and get no tiles.
         return register_at(s, "127.0.0.1:" + std::to_string(next_port++)); }},
      {"Heartbeat", [&](v1::Scheduler::Stub& s) {
         grpc::ClientContext c; set_deadline(c);
         v1::HeartbeatRequest r; r.set_worker_id("no-such-worker"); v1::HeartbeatResponse out;
         return s.Heartbeat(&c, r, &out); }},
  };

  constexpr Code OK = Code::OK, UN = Code::UNAUTHENTICATED, PD = Code::PERMISSION_DENIED;
  const std::vector<std::string> callers = {"none", "bad", "alice", "bob", "reader", "boss", "w1", "sched"};
  // One row per RPC, one column per caller, in the order of `callers`. A worker fetches only the
  // assets of calls in flight to it (none here), so even w1 may not GetAsset now.
  const std::map<std::string, std::vector<Code>> expected = {
      {"GetJob",                  {UN, UN, OK, PD, OK, OK, PD, PD}},
      {"ListJobs",                {UN, UN, OK, OK, OK, OK, PD, PD}},
      {"WatchJob",                {UN, UN, OK, PD, OK, OK, PD, PD}},
      {"GetResult",               {UN, UN, OK, PD, OK, OK, PD, PD}},
      {"CancelJob",               {UN, UN, OK, PD, PD, OK, PD, PD}},
      {"HasAssets",               {UN, UN, OK, OK, PD, OK, PD, PD}},
      {"UploadAsset",             {UN, UN, OK, OK, PD, OK, PD, PD}},
      {"SubmitJob",               {UN, UN, OK, OK, PD, OK, PD, PD}},
      {"SubmitJob priority 1000", {UN, UN, PD, PD, PD, OK, PD, PD}},
      {"GetAsset",                {UN, UN, PD, PD, PD, OK, PD, PD}},
      {"RegisterWorker",          {UN, UN, PD, PD, PD, OK, OK, PD}},
      {"Heartbeat",               {UN, UN, PD, PD, PD, OK, OK, PD}},
  };
  ASSERT_EQ(expected.size(), rpcs.size());
  for (const auto& [rpc, codes] : expected) {
    for (std::size_t i = 0; i < callers.size(); ++i) {
      auto stub = test::scheduler_stub(scheduler.address(), as(callers[i]));
      const grpc::Status status = rpcs.at(rpc)(*stub);
      EXPECT_EQ(status.error_code(), codes[i])
          << rpc << " by " << callers[i] << ": " << status.error_message();
    }
  }

  // A worker cannot take over an address another caller registered; an admin can.
  auto boss = test::scheduler_stub(scheduler.address(), as("boss"));
  auto w1 = test::scheduler_stub(scheduler.address(), as("w1"));
  ASSERT_TRUE(register_at(*boss, "127.0.0.1:7").ok());
  EXPECT_EQ(register_at(*w1, "127.0.0.1:7").error_code(), Code::PERMISSION_DENIED);
  ASSERT_TRUE(register_at(*w1, "127.0.0.1:8").ok());
  EXPECT_TRUE(register_at(*boss, "127.0.0.1:8").ok());

  // A submitter lists only its own jobs; a reader lists everyone's.
  auto list = [&](const std::string& caller) {
    auto stub = test::scheduler_stub(scheduler.address(), as(caller));
    grpc::ClientContext c;
    set_deadline(c);
    v1::ListJobsResponse out;
    EXPECT_TRUE(stub->ListJobs(&c, v1::ListJobsRequest(), &out).ok());
    std::map<std::string, int> owners;
    for (const v1::Job& j : out.jobs()) ++owners[j.owner()];
    return owners;
  };
  EXPECT_EQ(list("alice"), (std::map<std::string, int>{{"alice", 2}}));  // her job + SubmitJob's
  EXPECT_EQ(list("bob"), (std::map<std::string, int>{{"bob", 1}}));
  EXPECT_EQ(list("reader"), (std::map<std::string, int>{{"alice", 2}, {"bob", 1}, {"boss", 2}}));

  // No token ever reaches the log.
  const std::string log = scheduler.process().output();
  for (const auto& [name, token] : kTokens) EXPECT_EQ(log.find(token), std::string::npos) << name;
}

// A worker with --tokens renders only for a caller with the scheduler (or admin) role; a
// scheduler given such a token (--token-file) renders on it.
TEST_F(FarmAccessTest, AWorkerWithTokensServesOnlyTheSchedulerRole) {
  test::WorkerProcess worker({"--threads", "1", "--cache-dir", (dir / "w").string(), "--tokens", tokens.string()});
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  auto render_as = [&](const std::string& caller) {
    auto channel = open_channel(worker.address(), as(caller));
    auto stub = v1::Worker::NewStub(channel);
    grpc::ClientContext c;
    set_deadline(c);
    v1::RenderTileRequest r;
    *r.mutable_job() = test::cornell_job_spec("raster", 8, 8, 1);
    r.mutable_rect()->set_x1(8);
    r.mutable_rect()->set_y1(8);
    v1::RenderTileResponse out;
    return stub->RenderTile(&c, r, &out).error_code();
  };
  EXPECT_EQ(render_as("none"), Code::UNAUTHENTICATED);
  EXPECT_EQ(render_as("bad"), Code::UNAUTHENTICATED);
  EXPECT_EQ(render_as("alice"), Code::PERMISSION_DENIED);
  EXPECT_EQ(render_as("w1"), Code::PERMISSION_DENIED);
  // Allowed in: the worker lacks the job's files, which is the next thing it says.
  EXPECT_EQ(render_as("sched"), Code::FAILED_PRECONDITION);

  const fs::path sched_token = dir.write("sched.token", kTokens.at("sched") + "\n");
  test::SchedulerProcess scheduler(dir / "data", {"--worker", worker.address(), "--token-file", sched_token.string()});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  auto stub = test::scheduler_stub(scheduler.address());
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  v1::Job job;
  ASSERT_TRUE(test::submit(*stub, test::cornell_job_spec("raster", 24, 16, 1), job).ok());
  const auto done = test::wait_for_job(*stub, job.job_id(), [](const v1::Job& j) { return is_final(j.state()); }, 60s);
  ASSERT_TRUE(done && done->state() == v1::JOB_STATE_SUCCEEDED) << (done ? done->failure_reason() : "timeout");
}

// The CLI sends --token-file or FARM_TOKEN; without one a tokens scheduler says what is missing.
TEST_F(FarmAccessTest, ClientCommandsSendTheTokenFromAFileOrTheEnvironment) {
  test::SchedulerProcess scheduler(dir / "data", {"--tokens", tokens.string()});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  const std::string at = " --scheduler " + scheduler.address();

  const test::CommandResult none = test::run_command(test::farm_command("status" + at) + " 2>&1");
  EXPECT_EQ(none.exit_code, 1) << none.output;
  EXPECT_NE(none.output.find("no token"), std::string::npos) << none.output;

  const fs::path file = dir.write("reader.token", kTokens.at("reader") + "\n");
  const test::CommandResult by_file =
      test::run_command(test::farm_command("status" + at + " --token-file " + test::shell_quote(file.string())) + " 2>&1");
  EXPECT_EQ(by_file.exit_code, 0) << by_file.output;

  const test::CommandResult by_env = test::run_command(
      "FARM_TOKEN=" + kTokens.at("reader") + " " + test::farm_command("status" + at) + " 2>&1");
  EXPECT_EQ(by_env.exit_code, 0) << by_env.output;

  const test::CommandResult wrong = test::run_command(
      "FARM_TOKEN=" + kTokens.at("w1") + " " + test::farm_command("status" + at) + " 2>&1");
  EXPECT_EQ(wrong.exit_code, 1) << wrong.output;
  EXPECT_NE(wrong.output.find("PERMISSION_DENIED"), std::string::npos) << wrong.output;
}

// `farm token` prints a new token and the tokens-file line that grants it.
TEST_F(FarmAccessTest, FarmTokenMakesATokenAndTheLineThatGrantsIt) {
  auto make = [&](const std::string& name) {
    const fs::path err = dir / (name + ".err");
    const test::CommandResult r = test::run_command(
        "(" + test::farm_command("token " + name + " --roles read,submit") + " 2>" + test::shell_quote(err.string()) + ")");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::string token = r.output;
    while (!token.empty() && token.back() == '\n') token.pop_back();
    const std::string message = test::read_file(err);
    const std::size_t line = message.rfind('\n', message.size() - 2);
    return std::make_pair(token, message.substr(line + 1));
  };
  const auto [token, line] = make("carol");
  const auto [other, other_line] = make("dave");
  EXPECT_NE(token, other);
  EXPECT_EQ(line.find(token), std::string::npos) << "the line holds only the hash";
  const TokenTable table = TokenTable::load(dir.write("made.txt", line + other_line));
  const auto carol = table.find(token);
  ASSERT_TRUE(carol);
  EXPECT_EQ(carol->name, "carol");
  EXPECT_EQ(to_string(carol->roles), "submit,read");
  EXPECT_EQ(table.find(other)->name, "dave");
  EXPECT_EQ(test::run_command(test::farm_command("token eve --roles root")).exit_code, 2);
}

// Loopback by default; beyond it, authentication or --insecure.
TEST_F(FarmAccessTest, ServersRefuseANonLoopbackAddressWithoutAuthentication) {
  for (const std::string& server : {"scheduler --data-dir " + test::shell_quote((dir / "d").string()),
                                   std::string("worker")}) {
    const test::CommandResult refused =
        test::run_command(test::farm_command(server + " --listen 0.0.0.0:0") + " 2>&1");
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_NE(refused.output.find("refusing to listen on 0.0.0.0:0 without authentication"), std::string::npos)
        << refused.output;
    EXPECT_NE(refused.output.find("--insecure"), std::string::npos) << refused.output;
  }
  // With --insecure it starts, and says what it is doing.
  test::BackgroundProcess insecure({FARM_BINARY, "worker", "--listen", "0.0.0.0:0", "--insecure"});
  EXPECT_FALSE(wait_for_listening(insecure, "worker", 30s).empty()) << insecure.output();
  EXPECT_NE(insecure.output().find("no authentication"), std::string::npos) << insecure.output();
  // A tokens file is authentication enough (with a warning that tokens travel in plain text).
  test::BackgroundProcess with_tokens({FARM_BINARY, "worker", "--listen", "0.0.0.0:0", "--tokens", tokens.string()});
  EXPECT_FALSE(wait_for_listening(with_tokens, "worker", 30s).empty()) << with_tokens.output();
  EXPECT_NE(with_tokens.output().find("plain text"), std::string::npos) << with_tokens.output();
  // The default is loopback.
  test::BackgroundProcess by_default({FARM_BINARY, "worker"});
  EXPECT_NE(wait_for_listening(by_default, "worker", 30s).find("127.0.0.1:"), std::string::npos)
      << by_default.output();
}

}  // namespace
}  // namespace farm
