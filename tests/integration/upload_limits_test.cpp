// UploadAsset cannot be held open to starve the farm (issue #32: 40 idle streams announcing 2 GiB
// each held the whole asset quota): a stream that sends nothing for --upload-idle-timeout is
// ended and its reservation freed, and one owner's uploads in flight hold at most a quarter of
// --max-asset-store-bytes, so that another owner can still upload.
#include <gtest/gtest.h>
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "proto/farm.grpc.pb.h"
#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

const std::string kAlice = "alice-token-0123456789abcdef";
const std::string kBob = "bob-token-0123456789abcdef01";

// An UploadAsset stream that has sent its header and then whatever the test sends.
struct OpenUpload {
  grpc::ClientContext context;
  v1::UploadAssetResponse response;
  std::unique_ptr<grpc::ClientWriter<v1::UploadAssetRequest>> writer;

  OpenUpload(v1::Scheduler::Stub& stub, const std::string& bytes, std::uint64_t announced) {
    context.set_deadline(std::chrono::system_clock::now() + 120s);
    writer = stub.UploadAsset(&context, &response);
    v1::UploadAssetRequest header;
    header.mutable_header()->set_sha256(sha256_hex(bytes));
    header.mutable_header()->set_size(announced);
    writer->Write(header);
  }
  grpc::Status finish(const std::string& data = {}) {
    if (!data.empty()) {
      v1::UploadAssetRequest part;
      part.set_data(data);
      writer->Write(part);
    }
    writer->WritesDone();
    return writer->Finish();
  }
};

TEST(UploadLimitsTest, AnIdleUploadIsEndedAndOneOwnerHoldsAQuarterOfTheQuotaAtMost) {
  test::TempDir dir;
  const auto tokens = dir.write("tokens.txt", sha256_hex(kAlice) + " alice submit\n" + sha256_hex(kBob) + " bob submit\n");
  test::SchedulerProcess scheduler(dir / "data", {"--tokens", tokens.string(), "--max-asset-store-bytes", "4000",
                                                  "--upload-idle-timeout", "10"});
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  auto alice = test::scheduler_stub(scheduler.address(), ClientIdentity{kAlice, false, {}});
  auto bob = test::scheduler_stub(scheduler.address(), ClientIdentity{kBob, false, {}});
  const std::string a(900, 'a'), b(900, 'b'), c(200, 'c');

  // Alice announces 900 bytes and goes quiet: the quota holds them for her. When the scheduler
  // has read her header is seen, not guessed: an upload announcing more than the whole store is
  // refused, changing nothing, with the bytes in flight named.
  OpenUpload idle(*alice, a, a.size());
  bool reserved = false;
  for (int tries = 0; tries < 6000 && !reserved; ++tries) {
    OpenUpload probe(*bob, b, 4001);
    const grpc::Status s = probe.finish();
    ASSERT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
    reserved = s.error_message().find("(900 more being uploaded)") != std::string::npos;
    if (!reserved) std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(reserved) << "alice's quiet upload was never reserved";
  // A second upload of hers would pass her share of 1000 (a quarter of 4000)...
  {
    OpenUpload more(*alice, c, c.size());
    const grpc::Status s = more.finish(c);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
    EXPECT_NE(s.error_message().find("share of 1000"), std::string::npos) << s.error_message();
  }
  // ...while Bob still uploads.
  {
    OpenUpload upload(*bob, b, b.size());
    const grpc::Status s = upload.finish(b);
    EXPECT_TRUE(s.ok()) << s.error_message();
  }
  // The quiet stream is ended by the scheduler (Finish returns once it is; bounded by the
  // context's deadline), and Alice uploads again.
  const grpc::Status ended = idle.writer->Finish();
  EXPECT_FALSE(ended.ok());
  EXPECT_NE(ended.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << "the client's own deadline ended it, not the scheduler";
  // Its reservation is freed as its handler unwinds, just after the client hears the end: seen,
  // not guessed, as above (the in-flight bytes a refusal names drop from 900).
  // (The probe names bytes no one stored: Bob's are, and would be answered at once.)
  const std::string unstored(901, 'p');
  bool freed = false;
  for (int tries = 0; tries < 6000 && !freed; ++tries) {
    OpenUpload probe(*bob, unstored, 4001);
    const grpc::Status p = probe.finish();
    ASSERT_EQ(p.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << p.error_message();
    freed = p.error_message().find("(900 more being uploaded)") == std::string::npos;
    if (!freed) std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(freed) << "the ended upload's reservation was never freed";
  OpenUpload again(*alice, c, c.size());
  const grpc::Status s = again.finish(c);
  EXPECT_TRUE(s.ok()) << s.error_message();
}

}  // namespace
}  // namespace farm
