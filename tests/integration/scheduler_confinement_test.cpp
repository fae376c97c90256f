// The scheduler validates a job by loading its models from its own copy of the job's files
// (<data>/scenes/<scene hash>/). A raw SubmitJob, from no client of ours, may carry a model that
// names a file past that folder: an OBJ's `mtllib ../../../elsewhere/secret.mtl`, an absolute path,
// a glTF buffer or image, a folder. Each must be INVALID_ARGUMENT naming the model and the path,
// with nothing opened; and an AssetRef whose size differs from its blob's is refused too.
//
// Links and FIFOs cannot come from a spec (assets are laid out as plain files), so those cases put
// them into the scene folder beforehand, as something else on the machine could: the loader must
// refuse them all the same, and a FIFO must never make SubmitJob wait.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/common/scene_hash.h"
#include "server/common/sha256.h"
#include "tests/support/confinement_fixtures.h"
#include "tests/support/job_specs.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Escape;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

using Reference = test::ModelReference;
using ServerCase = test::ConfinementCase;

// SubmitJob with a deadline well past the FifoReleaser's grace: a scheduler stuck on a FIFO is
// released, accepts the job, and the test fails on that.
grpc::Status submit(v1::Scheduler::Stub& stub, const v1::JobSpec& spec) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 120s);
  v1::SubmitJobRequest request;
  *request.mutable_job() = spec;
  v1::SubmitJobResponse response;
  return stub.SubmitJob(&context, request, &response);
}

class SchedulerJob : public ::testing::Test {
 protected:
  void SetUp() override {
    scheduler_ = std::make_unique<test::SchedulerProcess>(dir_ / "data", std::vector<std::string>{});
    ASSERT_FALSE(scheduler_->address().empty()) << scheduler_->process().output();
    stub_ = test::scheduler_stub(scheduler_->address());
  }

  // The job: one model whose reference is `reference`, with the files the spec carries.
  v1::JobSpec crafted_spec(Reference kind, const std::string& reference) {
    test::CraftedModel crafted = test::craft_model(dir_, kind, reference);
    model_ = crafted.model;
    files_ = std::move(crafted.files);
    return test::make_job_spec(R"({"version": 1, "scene": {"objects": [{"file": ")" + model_ + R"("}]}})",
                               files_, "job.json");
  }

  test::TempDir dir_;
  std::unique_ptr<test::SchedulerProcess> scheduler_;
  std::unique_ptr<v1::Scheduler::Stub> stub_;
  std::string model_;
  std::vector<std::pair<std::string, fs::path>> files_;
};

class SchedulerConfinement : public SchedulerJob, public ::testing::WithParamInterface<ServerCase> {};

TEST_P(SchedulerConfinement, RawSubmitJobIsInvalidArgumentNamingModelAndPathWithNothingOpened) {
  ASSERT_TRUE(stub_);
  const ServerCase c = GetParam();
  const fs::path secret = dir_.write("elsewhere/secret.mtl", test::secret_mtl());
  const std::string name = "link.dat";
  // The scene folder is <data>/scenes/<hash>: `..` three times reaches dir_, whatever the hash.
  const std::string reference = c.escape == Escape::dot_dot    ? "../../../elsewhere/secret.mtl"
                                : c.escape == Escape::absolute ? secret.string()
                                                               : name;
  v1::JobSpec spec = crafted_spec(c.reference, reference);
  if (c.escape == Escape::directory) {
    // Straight from a spec: the folder of another asset.
    files_.emplace_back(name + "/placeholder.txt", dir_.write("files/placeholder.txt", "x"));
    spec = test::make_job_spec(spec.job_json(), files_, "job.json");
  }
  ASSERT_TRUE(test::upload_assets(*stub_, files_).ok());

  const fs::path scene = dir_ / "data/scenes" / scene_hash(spec);
  const test::PlacedEscape placed = test::place_escape_in_scene(c.escape, scene, files_, secret, name);
  const fs::path& target = placed.target;
  test::OpenWatch watch(target);
  ASSERT_TRUE(watch.watching()) << target;
  const test::FifoReleaser releaser(placed.fifos, 20s);

  const grpc::Status status = submit(*stub_, spec);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  const std::string& message = status.error_message();
  EXPECT_TRUE(contains(message, model_ + ": '" + reference + "'")) << message;
  EXPECT_TRUE(contains(message, "job.json: scene.objects[0].file: ")) << message;
  EXPECT_FALSE(contains(message, test::kSecretMarker)) << message;
  EXPECT_FALSE(contains(message, (dir_ / "data").string())) << "the scheduler's folders are not shown: " << message;
  EXPECT_FALSE(watch.opened()) << target << " was opened";
  EXPECT_FALSE(releaser.released_a_reader()) << "SubmitJob waited on the FIFO";
}

INSTANTIATE_TEST_SUITE_P(EveryReferenceAndEscape, SchedulerConfinement, ::testing::ValuesIn(test::all_confinement_cases()),
                         test::confinement_case_name);

// What is allowed stays allowed: the same model naming a library beside it is accepted.
TEST_F(SchedulerJob, AModelNamingAFileInsideItsJobIsAccepted) {
  ASSERT_TRUE(stub_);
  v1::JobSpec spec = crafted_spec(Reference::obj_mtllib, "plain.mtl");
  files_.emplace_back("plain.mtl", dir_.write("files/plain.mtl", test::plain_mtl()));
  spec = test::make_job_spec(spec.job_json(), files_, "job.json");
  ASSERT_TRUE(test::upload_assets(*stub_, files_).ok());
  const grpc::Status status = submit(*stub_, spec);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// AssetRef.size must be the blob's: larger or smaller, the job is refused naming the asset.
TEST_F(SchedulerJob, AnAssetRefWhoseSizeDiffersFromTheBlobIsInvalidArgumentNamingThePath) {
  ASSERT_TRUE(stub_);
  v1::JobSpec spec = crafted_spec(Reference::obj_mtllib, "plain.mtl");
  files_.emplace_back("plain.mtl", dir_.write("files/plain.mtl", test::plain_mtl()));
  spec = test::make_job_spec(spec.job_json(), files_, "job.json");
  ASSERT_TRUE(test::upload_assets(*stub_, files_).ok());
  for (const std::int64_t delta : {1, -1}) {
    v1::JobSpec lying = spec;
    v1::AssetRef& ref = *lying.mutable_assets(1);
    ASSERT_EQ(ref.path(), "plain.mtl");
    ref.set_size(static_cast<std::uint64_t>(static_cast<std::int64_t>(ref.size()) + delta));
    const grpc::Status status = submit(*stub_, lying);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_TRUE(contains(status.error_message(), "asset 'plain.mtl'")) << status.error_message();
    EXPECT_TRUE(contains(status.error_message(), std::to_string(ref.size()) + " bytes")) << status.error_message();
  }
  EXPECT_TRUE(submit(*stub_, spec).ok());  // the truthful spec still goes
}

}  // namespace
}  // namespace farm
