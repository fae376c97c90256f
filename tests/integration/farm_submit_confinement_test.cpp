// `farm submit` and `farm render` from the command line, with a model that names a file it may not
// (`..` out of the asset root, an absolute path, a link out, a FIFO, a folder): exit code 2, the
// model and the path named, the target never opened, and nothing sent: the scheduler holds no job
// and not the secret's bytes. And an AssetRef whose size is not its file's is refused.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "proto/farm.grpc.pb.h"
#include "renderer/util/input_error.h"
#include "server/client/job_submission.h"
#include "server/client/scheduler_client.h"
#include "server/common/sha256.h"
#include "tests/support/confinement_fixtures.h"
#include "tests/support/farm_cli_fixture.h"
#include "tests/support/job_specs.h"
#include "tests/support/scheduler_client.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Escape;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

enum class Model { obj_mtllib, gltf_buffer };

struct CliCase {
  Model model;
  Escape escape;
};

std::string case_name(const ::testing::TestParamInfo<CliCase>& info) {
  return std::string(info.param.model == Model::obj_mtllib ? "ObjMtllib" : "GltfBuffer") + "_" +
         test::to_string(info.param.escape);
}

std::vector<CliCase> all_cases() {
  std::vector<CliCase> cases;
  for (Model m : {Model::obj_mtllib, Model::gltf_buffer}) {
    for (Escape e : test::kAllEscapes) cases.push_back({m, e});
  }
  return cases;
}

class FarmSubmitConfinement : public ::testing::TestWithParam<CliCase> {
 protected:
  void SetUp() override {
    const CliCase c = GetParam();
    const fs::path models = dir_ / "root/models";
    const std::string name = c.model == Model::obj_mtllib ? "link.mtl" : "link.bin";
    secret_ = dir_ / "elsewhere/secret.mtl";
    reference_ = test::make_escape(c.escape, models, secret_, name);
    model_ = c.model == Model::obj_mtllib ? "tri.obj" : "tri.gltf";
    dir_.write("root/models/" + model_, c.model == Model::obj_mtllib ? test::triangle_obj(reference_)
                                                                      : test::triangle_gltf(reference_));
    job_ = dir_.write("root/job.json", R"({"version": 1, "scene": {"objects": [{"file": "models/)" + model_ +
                                           R"("}]}, "render": {"width": 8, "height": 8}})");
    target_ = test::escape_target(c.escape, models, secret_, name);
    if (c.escape == Escape::fifo) fifos_.push_back(target_);
  }

  void expect_refused(const test::CommandResult& r) const {
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_TRUE(contains(r.output, model_ + ": '" + reference_ + "'")) << r.output;
    EXPECT_FALSE(contains(r.output, test::kSecretMarker)) << r.output;
  }

  test::TempDir dir_;
  fs::path secret_, job_, target_;
  std::string model_, reference_;
  std::vector<fs::path> fifos_;
};

TEST_P(FarmSubmitConfinement, SubmitExitsWith2NamingModelAndPathAndUploadsNothing) {
  auto scheduler = std::make_unique<test::SchedulerProcess>(dir_ / "data", std::vector<std::string>{});
  ASSERT_FALSE(scheduler->address().empty()) << scheduler->process().output();
  test::OpenWatch watch(target_);
  ASSERT_TRUE(watch.watching());
  test::CommandResult r;
  {
    const test::FifoReleaser releaser(fifos_);  // a client stuck on the FIFO reads nothing and submits
    r = test::run_command(test::farm_command("submit " + test::shell_quote(job_.string()) + " --scheduler " +
                                             scheduler->address()));
    EXPECT_FALSE(releaser.released_a_reader()) << "farm submit waited on the FIFO";
  }
  expect_refused(r);
  EXPECT_FALSE(watch.opened()) << target_ << " was opened";

  // Nothing reached the scheduler: no job, and not the secret's bytes.
  auto stub = test::scheduler_stub(scheduler->address());
  grpc::ClientContext list_context;
  v1::ListJobsResponse jobs;
  ASSERT_TRUE(stub->ListJobs(&list_context, v1::ListJobsRequest(), &jobs).ok());
  EXPECT_EQ(jobs.jobs_size(), 0);
  grpc::ClientContext has_context;
  v1::HasAssetsRequest has;
  has.add_sha256(sha256_hex(test::secret_mtl()));
  v1::HasAssetsResponse missing;
  ASSERT_TRUE(stub->HasAssets(&has_context, has, &missing).ok());
  EXPECT_EQ(missing.missing_size(), 1) << "the scheduler holds the secret";
}

TEST_P(FarmSubmitConfinement, RenderExitsWith2NamingModelAndPath) {
  test::OpenWatch watch(target_);
  ASSERT_TRUE(watch.watching());
  test::CommandResult r;
  {
    const test::FifoReleaser releaser(fifos_);
    r = test::run_command("cd " + test::shell_quote(dir_.path().string()) + " && " +
                          test::farm_command("render " + test::shell_quote(job_.string()) + " --quiet"));
    EXPECT_FALSE(releaser.released_a_reader()) << "farm render waited on the FIFO";
  }
  expect_refused(r);
  EXPECT_FALSE(watch.opened()) << target_ << " was opened";
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "an image was written";
}

INSTANTIATE_TEST_SUITE_P(EveryEscape, FarmSubmitConfinement, ::testing::ValuesIn(all_cases()), case_name);

// The client's AssetRefs carry the size of the bytes it hashed and uploads; one that says
// otherwise (a client of another make, or a file changed under it) is refused by the scheduler,
// and the client reports it as bad input (exit 2 in `farm submit`) naming the path.
TEST(FarmSubmitAssetSizes, ASubmissionWhoseAssetRefSizeDiffersFromItsFileIsRefusedNamingThePath) {
  test::TempDir dir;
  dir.write("root/models/plain.mtl", test::plain_mtl());
  dir.write("root/models/tri.obj", test::triangle_obj("plain.mtl"));
  const fs::path job = dir.write("root/job.json", R"({"version": 1, "scene": {"objects": [{"file": "models/tri.obj"}]},
                                                     "render": {"width": 8, "height": 8}})");
  auto scheduler = std::make_unique<test::SchedulerProcess>(dir / "data", std::vector<std::string>{});
  ASSERT_FALSE(scheduler->address().empty()) << scheduler->process().output();
  SchedulerClient client(scheduler->address());
  JobSubmission submission = make_job_submission(job, {}, {});
  for (const v1::AssetRef& ref : submission.spec.assets()) {
    EXPECT_EQ(ref.size(), test::read_file(dir / "root" / ref.path()).size()) << ref.path();
  }
  EXPECT_EQ(client.upload_missing(submission), 2u);
  ASSERT_EQ(submission.spec.assets(0).path(), "models/plain.mtl");
  submission.spec.mutable_assets(0)->set_size(submission.spec.assets(0).size() + 7);
  try {
    client.submit(submission, 0);
    ADD_FAILURE() << "a spec with a wrong size was accepted";
  } catch (const InputError& e) {
    EXPECT_TRUE(contains(e.what(), "asset 'models/plain.mtl'")) << e.what();
  }
}

// What `farm render` accepts, `farm submit` accepts (issue #32): a model named by an absolute path
// inside the asset root, and one named through a link inside it. Both are sent under the path they
// resolve to, the job text names them so, and a worker renders them.
TEST(FarmSubmitAssetSizes, AnAbsoluteInRootModelAndAnInRootLinkAreSubmittedAsFarmRenderTakesThem) {
  test::TempDir dir;
  dir.write("root/models/plain.mtl", test::plain_mtl());
  const fs::path model = dir.write("root/models/tri.obj", test::triangle_obj("plain.mtl"));
  fs::create_symlink("tri.obj", dir / "root/models/link.obj");
  test::LocalFarm farm = test::start_local_farm(dir / "farm", 1);
  ASSERT_TRUE(farm.problem.empty()) << farm.problem;
  for (const std::string& named : {model.string(), std::string("models/link.obj")}) {
    SCOPED_TRACE(named);
    const fs::path job = dir.write("root/job.json", R"({"version": 1, "scene": {"objects": [{"file": ")" + named +
                                                        R"("}]}, "render": {"width": 8, "height": 8}})");
    const test::CommandResult render =
        test::run_command(test::farm_command("render " + test::shell_quote(job.string()) + " --quiet --preview none"));
    EXPECT_EQ(render.exit_code, 0) << render.output;
    const test::CommandResult submit = test::run_command(test::farm_command(
        "submit " + test::shell_quote(job.string()) + " --wait --scheduler " + farm.address()));
    EXPECT_EQ(submit.exit_code, 0) << submit.output;
    const JobSubmission submission = make_job_submission(job, {}, {});
    EXPECT_TRUE(contains(submission.spec.job_json(), "\"models/tri.obj\"")) << submission.spec.job_json();
  }
}

}  // namespace
}  // namespace farm
