// grpc.health.v1.Health on the real `farm scheduler` and `farm worker`, as stock tools reach it:
// through server reflection alone (tests/python/health_reflection.py knows no .proto file and
// has no health stubs: what grpcurl does), in the wire format Kubernetes' gRPC probe and
// grpc_health_probe send by hand, and as a Watch that ends when the server is stopped.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "proto/health.grpc.pb.h"
#include "tests/support/background_process.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using grpc::health::v1::HealthCheckRequest;
using grpc::health::v1::HealthCheckResponse;

// tests/python/health_reflection.py against `address`, checking "", `service` and a name no
// farm server has.
test::CommandResult reflect_and_check(const std::string& address, const std::string& service) {
  EXPECT_TRUE(fs::exists(FARM_TEST_PYTHON))
      << FARM_TEST_PYTHON << " is missing: run deploy/install-deps.sh, which makes the test venv";
  return test::run_command(
      test::shell_quote(FARM_TEST_PYTHON) + " " +
      test::shell_quote((test::kSource / "tests/python/health_reflection.py").string()) +
      " --server " + test::shell_quote(address) + " --check '' --check " +
      test::shell_quote(service) + " --check no.such.Service 2>&1");
}

void expect_serving_through_reflection(const test::CommandResult& r, const std::string& service) {
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("service grpc.health.v1.Health\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("service " + service + "\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check \"\" SERVING\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check \"" + service + "\" SERVING\n"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check \"no.such.Service\" error NOT_FOUND: "), std::string::npos)
      << r.output;
}

// Check with a request encoded by hand from the spec, as the probes do; the reply's bytes.
std::string raw_check(const std::string& address, const std::string& request_bytes,
                      grpc::Status& status) {
  grpc::GenericStub stub(grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 60s);
  grpc::Slice slice(request_bytes);
  const grpc::ByteBuffer request(&slice, 1);
  grpc::CompletionQueue queue;
  auto call = stub.PrepareUnaryCall(&context, "/grpc.health.v1.Health/Check", request, &queue);
  call->StartCall();
  grpc::ByteBuffer reply;
  call->Finish(&reply, &status, nullptr);
  void* tag = nullptr;
  bool ok = false;
  queue.Next(&tag, &ok);  // the one event: Finish
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
  std::vector<grpc::Slice> slices;
  std::string bytes;
  if (status.ok() && reply.Dump(&slices).ok()) {
    for (const grpc::Slice& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  return bytes;
}

// A Watch of the server as a whole is told SERVING, then, once the server gets SIGTERM,
// NOT_SERVING, and ends with UNAVAILABLE; the server then exits cleanly. NOT_SERVING arriving
// shows the Watch was ended by the shutdown itself, not cancelled when the grace period ran out.
void expect_watch_ends_at_sigterm(const std::string& address, test::BackgroundProcess& process) {
  {
    auto stub = grpc::health::v1::Health::NewStub(
        grpc::CreateChannel(address, grpc::InsecureChannelCredentials()));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 60s);
    auto reader = stub->Watch(&context, HealthCheckRequest());
    HealthCheckResponse response;
    ASSERT_TRUE(reader->Read(&response)) << reader->Finish().error_message();
    EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);

    process.send_signal(SIGTERM);
    ASSERT_TRUE(reader->Read(&response)) << reader->Finish().error_message();
    EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
    EXPECT_FALSE(reader->Read(&response)) << "a status after NOT_SERVING: " << response.status();
    const grpc::Status status = reader->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  }
  // The channel is gone: a shutting-down server waits for its clients' connections to close,
  // and an idle synchronous client would only notice the server's GOAWAY when it next polls.
  const std::optional<int> code = process.wait_exit(60s);
  ASSERT_TRUE(code.has_value()) << "still running after SIGTERM\n" << process.output();
  EXPECT_EQ(*code, 0) << process.output();
}

class FarmHealthTest : public ::testing::Test {
 protected:
  std::unique_ptr<test::SchedulerProcess> start_scheduler() {
    auto scheduler = std::make_unique<test::SchedulerProcess>(dir_ / "data", std::vector<std::string>{});
    EXPECT_FALSE(scheduler->address().empty()) << scheduler->process().output();
    return scheduler;
  }
  std::unique_ptr<test::WorkerProcess> start_worker() {
    auto worker = std::make_unique<test::WorkerProcess>(
        std::vector<std::string>{"--threads", "1", "--cache-dir", (dir_ / "cache").string()});
    EXPECT_FALSE(worker->address().empty()) << worker->process().output();
    return worker;
  }

  test::TempDir dir_;
};

TEST_F(FarmHealthTest, SchedulerServesHealthThatReflectionAloneDescribes) {
  auto scheduler = start_scheduler();
  ASSERT_FALSE(scheduler->address().empty());
  expect_serving_through_reflection(reflect_and_check(scheduler->address(), "farm.v1.Scheduler"),
                                    "farm.v1.Scheduler");
}

TEST_F(FarmHealthTest, WorkerServesHealthThatReflectionAloneDescribes) {
  auto worker = start_worker();
  ASSERT_FALSE(worker->address().empty());
  expect_serving_through_reflection(reflect_and_check(worker->address(), "farm.v1.Worker"),
                                    "farm.v1.Worker");
}

// `farm health`, what container and Compose health checks run: exit 0 and SERVING from a live
// scheduler and worker (given a minute: a loaded machine is slow, not wrong), exit 1 from a worker
// stopped with SIGSTOP (it accepts connections but never answers) and from an address nobody
// listens on.
TEST_F(FarmHealthTest, FarmHealthCommandExitsZeroOnlyForAServingServer) {
  auto scheduler = start_scheduler();
  auto worker = start_worker();
  ASSERT_FALSE(scheduler->address().empty());
  ASSERT_FALSE(worker->address().empty());
  const std::string farm = test::shell_quote(FARM_BINARY);
  test::CommandResult r = test::run_command(farm + " health --scheduler " + scheduler->address() + " --timeout 60s 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, scheduler->address() + ": SERVING\n");
  r = test::run_command(farm + " health " + worker->address() + " --timeout 60s 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, worker->address() + ": SERVING\n");

  worker->process().send_signal(SIGSTOP);
  r = test::run_command(farm + " health " + worker->address() + " --timeout 2s 2>&1");
  worker->process().send_signal(SIGCONT);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(worker->address() + ": no answer: "), std::string::npos) << r.output;

  r = test::run_command(farm + " health localhost:1 --timeout 2s 2>&1");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("localhost:1: no answer: "), std::string::npos) << r.output;
}

TEST_F(FarmHealthTest, CheckSpeaksTheSpecsWireFormat) {
  auto worker = start_worker();
  ASSERT_FALSE(worker->address().empty());
  grpc::Status status;
  // HealthCheckRequest{} is no bytes; HealthCheckResponse{status: SERVING} is field 1 (varint
  // tag 0x08) = 1. What grpc_health_probe and Kubernetes send and read.
  EXPECT_EQ(raw_check(worker->address(), "", status), std::string("\x08\x01", 2));
  EXPECT_TRUE(status.ok()) << status.error_message();
  // HealthCheckRequest{service: "farm.v1.Worker"}: field 1, length-delimited (tag 0x0a).
  EXPECT_EQ(raw_check(worker->address(), std::string("\x0a\x0e") + "farm.v1.Worker", status),
            std::string("\x08\x01", 2));
  EXPECT_TRUE(status.ok()) << status.error_message();
  raw_check(worker->address(), std::string("\x0a\x03") + "nop", status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
}

TEST_F(FarmHealthTest, WorkerWatchSaysNotServingAndEndsAtSigterm) {
  auto worker = start_worker();
  ASSERT_FALSE(worker->address().empty());
  expect_watch_ends_at_sigterm(worker->address(), worker->process());
}

TEST_F(FarmHealthTest, SchedulerWatchSaysNotServingAndEndsAtSigterm) {
  auto scheduler = start_scheduler();
  ASSERT_FALSE(scheduler->address().empty());
  expect_watch_ends_at_sigterm(scheduler->address(), scheduler->process());
}

}  // namespace
}  // namespace farm
