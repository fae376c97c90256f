// A worker loads a job from its own copy of the job's files (<cache>/scenes/<scene hash>/). A raw
// RenderTile, from no scheduler of ours, may carry a model that names a file past that folder (an
// OBJ's mtllib, a glTF's buffer or image: `..`, an absolute path, a folder), or assets whose size
// is not what the spec says. Each must be refused naming the path, with nothing opened.
//
// Links and FIFOs cannot come from a spec (assets are laid out as plain files), so those cases put
// them into the scene folder beforehand, as something else on the machine could: the loader must
// refuse them all the same, and a FIFO must never make RenderTile wait.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "server/common/asset_store.h"
#include "server/common/scene_hash.h"
#include "server/common/sha256.h"
#include "tests/support/background_process.h"
#include "tests/support/confinement_fixtures.h"
#include "tests/support/fake_scheduler.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Escape;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

using Reference = test::ModelReference;
using WorkerCase = test::ConfinementCase;

// RenderTile of the whole 8x8 image with a deadline well past the FifoReleaser's grace: a worker
// stuck on a FIFO is released, renders, and the test fails on that.
grpc::Status render(v1::Worker::Stub& stub, const v1::JobSpec& spec, const std::vector<std::string>& inline_files,
                    v1::RenderTileResponse& response) {
  v1::RenderTileRequest request;
  *request.mutable_job() = spec;
  request.set_scene_hash(scene_hash(spec));
  request.mutable_rect()->set_x1(8);
  request.mutable_rect()->set_y1(8);
  for (const std::string& bytes : inline_files) {
    v1::InlineAsset& asset = *request.add_assets();
    asset.set_data(bytes);
    asset.set_sha256(sha256_hex(bytes));
  }
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 120s);
  return stub.RenderTile(&context, request, &response);
}

class WorkerJob : public ::testing::Test {
 protected:
  void start_worker(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> args{"--threads", "1", "--cache-dir", (dir_ / "cache").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    worker_ = std::make_unique<test::WorkerProcess>(args);
    ASSERT_FALSE(worker_->address().empty()) << worker_->process().output();
    stub_ = v1::Worker::NewStub(grpc::CreateChannel(worker_->address(), grpc::InsecureChannelCredentials()));
  }

  // The job (8x8, raster): one model whose reference is `reference`, with the files it carries.
  v1::JobSpec crafted_spec(Reference kind, const std::string& reference) {
    test::CraftedModel crafted = test::craft_model(dir_, kind, reference);
    model_ = crafted.model;
    files_ = std::move(crafted.files);
    return remade_spec();
  }

  v1::JobSpec remade_spec() const {
    return test::make_job_spec(R"({"version": 1, "scene": {"objects": [{"file": ")" + model_ +
                                   R"("}], "camera": {"position": [0, 0, 3], "target": [0, 0, 0]}},
                                   "render": {"engine": "raster", "width": 8, "height": 8}})",
                               files_, "job.json");
  }

  std::vector<std::string> inline_files() const {
    std::vector<std::string> out;
    for (const auto& [path, file] : files_) out.push_back(test::read_file(file));
    return out;
  }

  test::TempDir dir_;
  std::unique_ptr<test::WorkerProcess> worker_;
  std::unique_ptr<v1::Worker::Stub> stub_;
  std::string model_;
  std::vector<std::pair<std::string, fs::path>> files_;
};

class WorkerConfinement : public WorkerJob, public ::testing::WithParamInterface<WorkerCase> {};

TEST_P(WorkerConfinement, RawRenderTileIsInvalidArgumentNamingModelAndPathWithNothingOpened) {
  start_worker();
  ASSERT_TRUE(stub_);
  const WorkerCase c = GetParam();
  const fs::path secret = dir_.write("elsewhere/secret.mtl", test::secret_mtl());
  const std::string name = "link.dat";
  // The scene folder is <cache>/scenes/<hash>: `..` three times reaches dir_, whatever the hash.
  const std::string reference = c.escape == Escape::dot_dot    ? "../../../elsewhere/secret.mtl"
                                : c.escape == Escape::absolute ? secret.string()
                                                               : name;
  v1::JobSpec spec = crafted_spec(c.reference, reference);
  if (c.escape == Escape::directory) {
    // Straight from a spec: the folder of another asset.
    files_.emplace_back(name + "/placeholder.txt", dir_.write("files/placeholder.txt", "x"));
    spec = remade_spec();
  }
  const fs::path scene = dir_ / "cache/scenes" / scene_hash(spec);
  const test::PlacedEscape placed = test::place_escape_in_scene(c.escape, scene, files_, secret, name);
  const fs::path& target = placed.target;
  test::OpenWatch watch(target);
  ASSERT_TRUE(watch.watching()) << target;
  const test::FifoReleaser releaser(placed.fifos, 20s);

  v1::RenderTileResponse response;
  const grpc::Status status = render(*stub_, spec, inline_files(), response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  const std::string& message = status.error_message();
  EXPECT_TRUE(contains(message, model_ + ": '" + reference + "'")) << message;
  EXPECT_TRUE(contains(message, "job.json: scene.objects[0].file: ")) << message;
  EXPECT_FALSE(contains(message, test::kSecretMarker)) << message;
  EXPECT_FALSE(watch.opened()) << target << " was opened";
  EXPECT_FALSE(releaser.released_a_reader()) << "RenderTile waited on the FIFO";
}

INSTANTIATE_TEST_SUITE_P(EveryReferenceAndEscape, WorkerConfinement, ::testing::ValuesIn(test::all_confinement_cases()),
                         test::confinement_case_name);

using WorkerAssetSizes = WorkerJob;

// The same job naming a file beside it renders.
TEST_F(WorkerJob, AModelNamingAFileInsideItsJobRenders) {
  start_worker();
  ASSERT_TRUE(stub_);
  crafted_spec(Reference::obj_mtllib, "plain.mtl");
  files_.emplace_back("plain.mtl", dir_.write("files/plain.mtl", test::plain_mtl()));
  v1::RenderTileResponse response;
  const grpc::Status status = render(*stub_, remade_spec(), inline_files(), response);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// Inline bytes not as long as their AssetRef says: refused naming the path, nothing kept.
TEST_F(WorkerAssetSizes, AnInlineAssetWhoseSizeDiffersFromItsAssetRefIsInvalidArgumentNamingThePath) {
  start_worker();
  ASSERT_TRUE(stub_);
  crafted_spec(Reference::obj_mtllib, "plain.mtl");
  files_.emplace_back("plain.mtl", dir_.write("files/plain.mtl", test::plain_mtl()));
  const v1::JobSpec spec = remade_spec();
  for (const std::int64_t delta : {1, -1}) {
    v1::JobSpec lying = spec;
    v1::AssetRef& ref = *lying.mutable_assets(1);
    ASSERT_EQ(ref.path(), "plain.mtl");
    ref.set_size(static_cast<std::uint64_t>(static_cast<std::int64_t>(ref.size()) + delta));
    v1::RenderTileResponse response;
    const grpc::Status status = render(*stub_, lying, inline_files(), response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
    EXPECT_TRUE(contains(status.error_message(), "inline asset 'plain.mtl'")) << status.error_message();
    EXPECT_FALSE(AssetStore(dir_ / "cache/blobs").has(ref.sha256())) << "kept although refused";
  }
  // A blob the worker already holds, named with the wrong size, is refused as well.
  const AssetStore store(dir_ / "cache/blobs");
  for (const std::string& bytes : inline_files()) store.add(bytes);
  v1::JobSpec lying = spec;
  lying.mutable_assets(1)->set_size(spec.assets(1).size() + 1);
  v1::RenderTileResponse response;
  grpc::Status status = render(*stub_, lying, {}, response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_TRUE(contains(status.error_message(), "asset 'plain.mtl'")) << status.error_message();
  status = render(*stub_, spec, {}, response);  // the truthful spec renders
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// Fetched bytes not as long as their AssetRef says: refused naming the path, nothing kept.
TEST_F(WorkerAssetSizes, AFetchedAssetWhoseSizeDiffersFromItsAssetRefIsRefusedNamingThePath) {
  test::FakeScheduler scheduler;
  start_worker({"--scheduler", scheduler.address()});
  ASSERT_TRUE(stub_);
  crafted_spec(Reference::obj_mtllib, "plain.mtl");
  files_.emplace_back("plain.mtl", dir_.write("files/plain.mtl", test::plain_mtl()));
  for (const std::string& bytes : inline_files()) scheduler.add_asset(bytes);
  const v1::JobSpec spec = remade_spec();
  for (const std::int64_t delta : {1, -1}) {
    v1::JobSpec lying = spec;
    v1::AssetRef& ref = *lying.mutable_assets(1);
    ASSERT_EQ(ref.path(), "plain.mtl");
    ref.set_size(static_cast<std::uint64_t>(static_cast<std::int64_t>(ref.size()) + delta));
    v1::RenderTileResponse response;
    const grpc::Status status = render(*stub_, lying, {}, response);
    EXPECT_FALSE(status.ok());
    EXPECT_TRUE(contains(status.error_message(), "asset 'plain.mtl'")) << status.error_message();
    EXPECT_TRUE(contains(status.error_message(), "bytes")) << status.error_message();
    EXPECT_FALSE(AssetStore(dir_ / "cache/blobs").has(ref.sha256())) << "kept although refused";
  }
  v1::RenderTileResponse response;
  const grpc::Status status = render(*stub_, spec, {}, response);  // the truthful spec renders
  EXPECT_TRUE(status.ok()) << status.error_message();
}

}  // namespace
}  // namespace farm
