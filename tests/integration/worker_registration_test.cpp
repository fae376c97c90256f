// What a registering worker may say (issue #32): its address is a HOST:PORT a scheduler can call
// (no unix: socket, no garbage), its thread count a real one, and its heartbeats come from the
// identity that registered it, so one worker token cannot keep another's worker alive. And a
// scheduler never takes its own address for a worker.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

const std::string kW1 = "worker-one-token-0123456789ab";
const std::string kW2 = "worker-two-token-0123456789ab";

grpc::Status register_worker(v1::Scheduler::Stub& stub, const std::string& address, int threads,
                             v1::RegisterWorkerResponse* out = nullptr) {
  grpc::ClientContext c;
  c.set_deadline(std::chrono::system_clock::now() + 30s);
  v1::RegisterWorkerRequest r;
  r.set_address(address);
  r.set_threads(threads);
  v1::RegisterWorkerResponse ignored;
  return stub.RegisterWorker(&c, r, out ? out : &ignored);
}

grpc::Status heartbeat(v1::Scheduler::Stub& stub, const std::string& worker_id, v1::HeartbeatResponse& out) {
  grpc::ClientContext c;
  c.set_deadline(std::chrono::system_clock::now() + 30s);
  v1::HeartbeatRequest r;
  r.set_worker_id(worker_id);
  return stub.Heartbeat(&c, r, &out);
}

TEST(WorkerRegistrationTest, AddressesAndThreadsAreCheckedAndAHeartbeatComesFromItsRegistrant) {
  test::TempDir dir;
  const auto tokens = dir.write("tokens.txt", sha256_hex(kW1) + " w1 worker\n" + sha256_hex(kW2) + " w2 worker\n");
  test::SchedulerProcess scheduler(dir / "data", {"--tokens", tokens.string()});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  auto w1 = test::scheduler_stub(scheduler.address(), ClientIdentity{kW1, false, {}});
  auto w2 = test::scheduler_stub(scheduler.address(), ClientIdentity{kW2, false, {}});

  for (const char* address : {"unix:/tmp/farm.sock", "garbage", "host:0", "host:99999", "a b:1", "http://h:1",
                              "host:", ":5000", "[zz::1]:5000"}) {
    const grpc::Status s = register_worker(*w1, address, 1);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << address << ": " << s.error_message();
  }
  for (int threads : {-1, -1000000, 5000}) {
    const grpc::Status s = register_worker(*w1, "127.0.0.1:9", threads);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << threads << ": " << s.error_message();
  }
  v1::RegisterWorkerResponse registered;
  ASSERT_TRUE(register_worker(*w1, "127.0.0.1:9", 4, &registered).ok());
  ASSERT_TRUE(register_worker(*w1, "[::1]:9", 0).ok());
  ASSERT_TRUE(register_worker(*w1, "worker-7.farm.example:50052", 2).ok());

  v1::HeartbeatResponse beat;
  const grpc::Status other = heartbeat(*w2, registered.worker_id(), beat);
  EXPECT_EQ(other.error_code(), grpc::StatusCode::PERMISSION_DENIED) << other.error_message();
  ASSERT_TRUE(heartbeat(*w1, registered.worker_id(), beat).ok());
  EXPECT_FALSE(beat.register_again());
  // An id nobody registered: register (again), whoever asks.
  ASSERT_TRUE(heartbeat(*w2, "no-such-worker", beat).ok());
  EXPECT_TRUE(beat.register_again());
}

// A port free a moment ago on 127.0.0.1.
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t length = sizeof a;
  const bool bound = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
                     getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length) == 0;
  close(fd);
  return bound ? ntohs(a.sin_port) : 0;
}

// `farm scheduler --worker <its own address>` answered every unit UNIMPLEMENTED, with the empty
// reason "ERROR: ", and failed every job: now it does not start, and says why.
TEST(WorkerRegistrationTest, ASchedulerRefusesItsOwnAddressAsAWorker) {
  test::TempDir dir;
  const int port = free_port();
  ASSERT_GT(port, 0);
  for (const std::string& worker : {"127.0.0.1:" + std::to_string(port), "localhost:" + std::to_string(port),
                                    "dns:///localhost:" + std::to_string(port)}) {
    const test::CommandResult r = test::run_command(
        "timeout 60 " + test::farm_command("scheduler --listen 127.0.0.1:" + std::to_string(port) + " --worker " +
                                           worker + " --data-dir " + (dir / "data").string()));
    EXPECT_EQ(r.exit_code, 2) << worker << "\n" << r.output;
    EXPECT_NE(r.output.find("this scheduler's own address"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace farm
