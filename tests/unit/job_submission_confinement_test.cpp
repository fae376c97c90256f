// The client gathers a job's files (make_job_submission, what `farm submit` and `farm render` send)
// through the same gate the loaders use: every reference a model makes that leaves the asset root
// (by `..`, an absolute path, a symbolic link) or names a FIFO or a folder is refused naming the
// model and the reference, before anything reads it, so nothing outside the root is ever sent.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>

#include "renderer/util/input_error.h"
#include "server/client/job_submission.h"
#include "server/common/sha256.h"
#include "tests/support/confinement_fixtures.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::Escape;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Which reference of which file tries to escape.
enum class Reference { obj_mtllib, mtl_map, gltf_buffer, gltf_image, collada_image };

const char* to_string(Reference r) {
  switch (r) {
    case Reference::obj_mtllib: return "ObjMtllib";
    case Reference::mtl_map: return "MtlMap";
    case Reference::gltf_buffer: return "GltfBuffer";
    case Reference::gltf_image: return "GltfImage";
    case Reference::collada_image: return "ColladaImage";
  }
  return "?";
}

struct ClientCase {
  Reference reference;
  Escape escape;
};

std::string case_name(const ::testing::TestParamInfo<ClientCase>& info) {
  return std::string(to_string(info.param.reference)) + "_" + test::to_string(info.param.escape);
}

class SubmissionConfinement : public ::testing::TestWithParam<ClientCase> {
 protected:
  void SetUp() override {
    const ClientCase c = GetParam();
    const fs::path models = dir_ / "root/models";
    reference_ = test::make_escape(c.escape, models, dir_ / "elsewhere/secret.mtl", "link.dat");
    std::string model;
    switch (c.reference) {
      case Reference::obj_mtllib:
        model = "tri.obj";
        named_by_ = model;
        dir_.write("root/models/tri.obj", test::triangle_obj(reference_));
        break;
      case Reference::mtl_map:
        model = "tri.obj";
        named_by_ = "plain.mtl";
        dir_.write("root/models/tri.obj", test::triangle_obj("plain.mtl"));
        dir_.write("root/models/plain.mtl", test::plain_mtl() + "map_Kd " + reference_ + "\n");
        break;
      case Reference::gltf_buffer:
        model = "tri.gltf";
        named_by_ = model;
        dir_.write("root/models/tri.gltf", test::triangle_gltf(reference_));
        break;
      case Reference::gltf_image:
        model = "tri.gltf";
        named_by_ = model;
        dir_.write("root/models/tri.bin", test::triangle_bin());
        dir_.write("root/models/tri.gltf", test::triangle_gltf("tri.bin", reference_));
        break;
      case Reference::collada_image:
        model = "tri.dae";
        named_by_ = model;
        dir_.write("root/models/tri.dae", "<COLLADA><library_images><image id=\"i\"><init_from>" + reference_ +
                                              "</init_from></image></library_images></COLLADA>");
        break;
    }
    model_ = model;
    job_ = dir_.write("root/job.json",
                      R"({"version": 1, "scene": {"objects": [{"file": "models/)" + model + R"("}]}})");
    if (c.escape == Escape::fifo) fifos_.push_back(models / reference_);
    watch_ = std::make_unique<test::OpenWatch>(
        test::escape_target(c.escape, models, dir_ / "elsewhere/secret.mtl", "link.dat"));
    ASSERT_TRUE(watch_->watching());
  }

  void TearDown() override {
    EXPECT_FALSE(watch_->opened()) << "what '" << reference_ << "' leads to was opened";
  }

  test::TempDir dir_;
  fs::path job_;
  std::string model_, named_by_, reference_;
  std::vector<fs::path> fifos_;
  std::unique_ptr<test::OpenWatch> watch_;  // on the secret, the FIFO or the folder
};

TEST_P(SubmissionConfinement, RefusedNamingTheModelAndThePathAndNothingIsRead) {
  const test::FifoReleaser releaser(fifos_);  // a scan stuck on the FIFO would read nothing and carry on
  try {
    const JobSubmission s = make_job_submission(job_, {}, {});
    std::string sent;
    for (const v1::AssetRef& a : s.spec.assets()) sent += a.path() + " ";
    ADD_FAILURE() << "submitted, sending " << sent;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_TRUE(contains(message, model_)) << message;
    EXPECT_TRUE(contains(message, named_by_)) << message;
    EXPECT_TRUE(contains(message, "'" + reference_ + "'")) << message;
    EXPECT_FALSE(contains(message, test::kSecretMarker)) << message;
  }
  EXPECT_FALSE(releaser.released_a_reader()) << "the client opened the FIFO and waited for a writer";
}

std::vector<ClientCase> all_cases() {
  std::vector<ClientCase> cases;
  for (Reference r : {Reference::obj_mtllib, Reference::mtl_map, Reference::gltf_buffer, Reference::gltf_image,
                      Reference::collada_image}) {
    for (Escape e : test::kAllEscapes) cases.push_back({r, e});
  }
  return cases;
}

INSTANTIATE_TEST_SUITE_P(EveryReferenceAndEscape, SubmissionConfinement, ::testing::ValuesIn(all_cases()),
                         case_name);

// A link inside the root that points inside is fine: the file goes under the name the model uses
// (where a worker lays it out), with the bytes of what it points at, and every size is the size of
// the bytes hashed.
TEST(SubmissionConfinementAllowed, ALinkThatStaysInsideGoesUnderItsOwnNameWithSizesOfTheBytes) {
  test::TempDir dir;
  dir.write("root/shared/plain.mtl", test::plain_mtl());
  dir.write("root/models/tri.obj", test::triangle_obj("inner.mtl"));
  fs::create_symlink("../shared/plain.mtl", dir / "root/models/inner.mtl");
  const fs::path job = dir.write("root/job.json", R"({"version": 1, "scene": {"objects": [{"file": "models/tri.obj"}]}})");
  const JobSubmission s = make_job_submission(job, {}, {});
  ASSERT_EQ(s.spec.assets_size(), 2);
  EXPECT_EQ(s.spec.assets(0).path(), "models/inner.mtl");
  EXPECT_EQ(s.spec.assets(1).path(), "models/tri.obj");
  for (const v1::AssetRef& a : s.spec.assets()) {
    const std::string bytes = test::read_file(dir / "root" / a.path());
    EXPECT_EQ(a.size(), bytes.size()) << a.path();
    EXPECT_EQ(a.sha256(), sha256_hex(bytes)) << a.path();
    ASSERT_EQ(s.files.count(a.sha256()), 1u);
    EXPECT_EQ(test::read_file(s.files.at(a.sha256())), bytes);  // what an upload reads
  }
}

}  // namespace
}  // namespace farm
