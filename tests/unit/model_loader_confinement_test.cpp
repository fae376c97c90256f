// The loaders `farm render` runs (and the scheduler and workers, on their copies of a job's files)
// open only what confine_file allows: an OBJ's material library, a glTF's buffers and images that
// leave the asset root by `..`, by an absolute path or by a symbolic link, or that name a FIFO or a
// folder, are refused naming the model and the reference, and never read.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "renderer/job/job.h"
#include "renderer/job/scene_builder.h"
#include "renderer/scene/model.h"
#include "renderer/util/input_error.h"
#include "tests/support/confinement_fixtures.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::Escape;

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

using Reference = test::ModelReference;
using LoaderCase = test::ConfinementCase;

// root/job.json, root/models/<model> naming the escape; elsewhere/secret.mtl beside the root.
class LoaderConfinement : public ::testing::TestWithParam<LoaderCase> {
 protected:
  void SetUp() override {
    root_ = fs::weakly_canonical(dir_ / "root");
    const fs::path models = root_ / "models";
    const LoaderCase c = GetParam();
    const std::string name = c.reference == Reference::obj_mtllib ? "link.mtl" : "link.bin";
    reference_ = test::make_escape(c.escape, models, dir_ / "elsewhere/secret.mtl", name);
    if (c.reference == Reference::obj_mtllib) {
      model_ = dir_.write("root/models/tri.obj", test::triangle_obj(reference_));
    } else {
      dir_.write("root/models/tri.bin", test::triangle_bin());
      model_ = dir_.write("root/models/tri.gltf", c.reference == Reference::gltf_buffer
                                                       ? test::triangle_gltf(reference_)
                                                       : test::triangle_gltf("tri.bin", reference_));
    }
    job_ = dir_.write("root/job.json", R"({"version": 1, "scene": {"objects": [{"file": "models/)" +
                                           model_.filename().string() + R"("}]}})");
    if (c.escape == Escape::fifo) fifos_.push_back(models / reference_);
    watch_ = std::make_unique<test::OpenWatch>(
        test::escape_target(c.escape, models, dir_ / "elsewhere/secret.mtl", name));
    ASSERT_TRUE(watch_->watching());
  }

  void TearDown() override {
    EXPECT_FALSE(watch_->opened()) << "what '" << reference_ << "' leads to was opened";
  }

  // The refusal: names the model and the reference as written, and holds nothing of the secret.
  void expect_refusal(const std::string& message) const {
    EXPECT_TRUE(contains(message, model_.filename().string())) << message;
    EXPECT_TRUE(contains(message, "'" + reference_ + "'")) << message;
    EXPECT_FALSE(contains(message, test::kSecretMarker)) << message;
  }

  test::TempDir dir_;
  fs::path root_, model_, job_;
  std::string reference_;
  std::vector<fs::path> fifos_;
  std::unique_ptr<test::OpenWatch> watch_;  // on the secret, the FIFO or the folder
};

TEST_P(LoaderConfinement, LoadModelRefusesTheReferenceNamingModelAndPath) {
  const test::FifoReleaser releaser(fifos_);  // a loader stuck on the FIFO would then read nothing and load
  try {
    load_model(model_, root_);
    ADD_FAILURE() << model_ << " loaded although it names '" << reference_ << "'";
  } catch (const InputError& e) {
    expect_refusal(e.what());
  }
  EXPECT_FALSE(releaser.released_a_reader()) << "the loader opened the FIFO and waited for a writer";
}

TEST_P(LoaderConfinement, BuildSceneOfAJobRefusesItNamingJobObjectModelAndPath) {
  const test::FifoReleaser releaser(fifos_);
  const Job job = load_job(job_);
  try {
    build_scene(job);
    ADD_FAILURE() << "the scene built although its model names '" << reference_ << "'";
  } catch (const InputError& e) {
    const std::string message = e.what();
    expect_refusal(message);
    EXPECT_TRUE(contains(message, job_.string() + ": scene.objects[0].file: ")) << message;
  }
  EXPECT_FALSE(releaser.released_a_reader());
}

INSTANTIATE_TEST_SUITE_P(EveryReferenceAndEscape, LoaderConfinement, ::testing::ValuesIn(test::all_confinement_cases()),
                         test::confinement_case_name);

// What stays allowed: files inside the root, also through a link that stays inside, and `..` that
// climbs to a folder of the root.
TEST(LoaderConfinementAllowed, LinksInsideTheRootAndDotDotWithinItLoad) {
  test::TempDir dir;
  const fs::path root = fs::weakly_canonical(dir / "root");
  dir.write("root/shared/plain.mtl", test::plain_mtl());
  fs::create_directories(root / "models");
  fs::create_symlink("../shared/plain.mtl", root / "models/inner.mtl");
  for (const std::string mtllib : {"inner.mtl", "../shared/plain.mtl"}) {
    SCOPED_TRACE(mtllib);
    const fs::path obj = dir.write("root/models/tri.obj", test::triangle_obj(mtllib));
    const Model model = load_model(obj, root);
    ASSERT_FALSE(model.materials.empty());
    bool green = false;
    for (const Material& m : model.materials) green = green || m.diffuse == glm::vec3(0.2f, 0.8f, 0.2f);
    EXPECT_TRUE(green) << "the library was not read";
  }
  dir.write("root/shared/tri.bin", test::triangle_bin());
  fs::create_symlink("../shared/tri.bin", root / "models/inner.bin");
  const fs::path gltf = dir.write("root/models/tri.gltf", test::triangle_gltf("inner.bin"));
  EXPECT_EQ(load_model(gltf, root).triangle_count(), 1u);
  // Without a root of its own a model is confined to its folder: ../shared is then outside.
  const fs::path outside = dir.write("root/models/up.gltf", test::triangle_gltf("../shared/tri.bin"));
  EXPECT_EQ(load_model(outside, root).triangle_count(), 1u);
  EXPECT_THROW(load_model(outside), InputError);
}

}  // namespace
}  // namespace farm
