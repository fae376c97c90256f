// `farm fetch` trusts no name a scheduler sends (issue #32): a spoofed scheduler over plain text
// answers with a job named "../../PWNED" and result files named "../x" or "..". Whatever it says,
// every file lands inside -o, one plain file name each.
#include <gtest/gtest.h>
#include <grpcpp/grpcpp.h>

#include <filesystem>
#include <memory>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/sha256.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

const std::string kJobId = "0123456789abcdef0123456789abcdef";

// A scheduler that lies: its job's name and its files' names climb out of any folder.
class SpoofedScheduler final : public v1::Scheduler::Service {
 public:
  explicit SpoofedScheduler(std::string file_name) : file_name_(std::move(file_name)) {
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(this);
    server_ = builder.BuildAndStart();
    if (server_ && port != 0) address_ = "127.0.0.1:" + std::to_string(port);
  }
  ~SpoofedScheduler() override {
    if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
  }
  const std::string& address() const { return address_; }

  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::Job* job) override {
    fill(*job);
    return grpc::Status::OK;
  }
  grpc::Status ListJobs(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsResponse* response) override {
    fill(*response->add_jobs());
    return grpc::Status::OK;
  }
  grpc::Status GetResult(grpc::ServerContext*, const v1::GetResultRequest*,
                         grpc::ServerWriter<v1::FileChunk>* writer) override {
    const std::string bytes = "not an image, and it must not land outside -o";
    v1::FileChunk chunk;
    chunk.set_file_name(file_name_);
    chunk.set_total_size(bytes.size());
    chunk.set_sha256(sha256_hex(bytes));
    chunk.set_data(bytes);
    writer->Write(chunk);
    return grpc::Status::OK;
  }

 private:
  static void fill(v1::Job& job) {
    job.set_job_id(kJobId);
    job.set_name("../../PWNED");
    job.set_state(v1::JOB_STATE_SUCCEEDED);
  }
  std::string file_name_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

// Every regular file under `root`, relative to it.
std::vector<std::string> files_under(const fs::path& root) {
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), root).string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(FarmFetchConfinementTest, NamesFromASpoofedSchedulerNeverLeadOutsideTheOutputFolder) {
  for (const char* file_name : {"", "..", "../../PWNED.exr", "/tmp/PWNED.exr", "a/../../b.exr"}) {
    SCOPED_TRACE(std::string("the scheduler's file name: '") + file_name + "'");
    test::TempDir dir;
    const fs::path out = dir / "a" / "b" / "out";
    fs::create_directories(out);
    SpoofedScheduler scheduler(file_name);
    ASSERT_FALSE(scheduler.address().empty());
    const test::CommandResult r = test::run_command(
        test::farm_command("fetch " + kJobId + " --scheduler " + scheduler.address() + " -o " + out.string()));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    // Everything written is in -o itself, and nothing anywhere else under the test's folder.
    const std::vector<std::string> all = files_under(dir.path());
    ASSERT_FALSE(all.empty()) << r.output;
    for (const std::string& f : all) {
      EXPECT_EQ(fs::path(f).parent_path(), fs::path("a/b/out")) << f << "\n" << r.output;
      EXPECT_EQ(f.find("/.."), std::string::npos) << f;
    }
    EXPECT_FALSE(fs::exists("/tmp/PWNED.exr"));
  }
}

}  // namespace
}  // namespace farm
