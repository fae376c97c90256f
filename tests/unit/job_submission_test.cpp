// What `farm submit` (and the embedded farm) send: the job text and every file it reads.
#include "server/client/job_submission.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "renderer/util/input_error.h"
#include "server/common/sha256.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = FARM_SOURCE_DIR;
using test::TempDir;

std::vector<std::string> asset_paths(const v1::JobSpec& spec) {
  std::vector<std::string> out;
  for (const v1::AssetRef& a : spec.assets()) out.push_back(a.path());
  return out;
}

// The error a submission refuses a model with: it names the model and says why.
void expect_outside_root_error(const fs::path& job, const std::string& model,
                               const std::string& why = "outside the asset root") {
  try {
    make_job_submission(job, {}, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(model), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

// A job of `copies_each` objects of each model, side by side.
std::string job_of_copies(const std::vector<std::string>& models, int copies_each) {
  nlohmann::json objects = nlohmann::json::array();
  for (int i = 0; i < copies_each; ++i) {
    for (const std::string& model : models) objects.push_back({{"file", model}, {"translate", {i, 0, 0}}});
  }
  return nlohmann::json{{"version", 1}, {"scene", {{"objects", objects}}}}.dump();
}

TEST(JobSubmission, JobInItsOwnFolderGoesByteForByteWithItsModelAndMaterials) {
  const fs::path job = kSource / "jobs/cornell.json";
  const JobSubmission s = make_job_submission(job, {}, {});
  EXPECT_EQ(s.spec.job_json(), test::read_file(job));
  EXPECT_EQ(s.spec.file_name(), "cornell.json");
  EXPECT_EQ(asset_paths(s.spec), (std::vector<std::string>{"assets/cornell_box.mtl", "assets/cornell_box.obj"}));
  for (const v1::AssetRef& a : s.spec.assets()) {
    const fs::path file = kSource / "jobs" / a.path();
    EXPECT_EQ(a.sha256(), sha256_file_hex(file)) << a.path();
    EXPECT_EQ(a.size(), fs::file_size(file)) << a.path();
    ASSERT_EQ(s.files.count(a.sha256()), 1u);
    EXPECT_EQ(fs::canonical(s.files.at(a.sha256())), fs::canonical(file));
  }
}

TEST(JobSubmission, AnEnvironmentMapTravelsWithTheJobAndItsPathIsRewrittenUnderTheRoot) {
  const fs::path job = kSource / "jobs/environment.json";
  const JobSubmission s = make_job_submission(job, {}, {});
  EXPECT_EQ(s.spec.job_json(), test::read_file(job));  // as written: every path already under the root
  EXPECT_EQ(asset_paths(s.spec),
            (std::vector<std::string>{"assets/sky.hdr", "assets/yard.mtl", "assets/yard.obj"}));
  // With the root above the job's folder, the map is named from the root like the model.
  JobLoadOptions load;
  load.asset_root = kSource;
  const JobSubmission above = make_job_submission(job, load, {});
  const auto doc = nlohmann::json::parse(above.spec.job_json());
  EXPECT_EQ(doc["scene"]["environment"]["map"], "jobs/assets/sky.hdr");
  EXPECT_EQ(doc["scene"]["objects"][0]["file"], "jobs/assets/yard.obj");
  EXPECT_EQ(asset_paths(above.spec),
            (std::vector<std::string>{"jobs/assets/sky.hdr", "jobs/assets/yard.mtl", "jobs/assets/yard.obj"}));
}

TEST(JobSubmission, OverridesAreWrittenIntoTheJobText) {
  RenderOverrides o;
  o.engine = "path";
  o.width = 64;
  o.spp = 3;
  o.preview = fs::path();  // none
  const JobSubmission s = make_job_submission(kSource / "jobs/cornell.json", {}, o);
  const auto doc = nlohmann::json::parse(s.spec.job_json());
  EXPECT_EQ(doc["render"]["engine"], "path");
  EXPECT_EQ(doc["render"]["width"], 64);
  EXPECT_EQ(doc["render"]["height"], 512);  // untouched
  EXPECT_EQ(doc["render"]["spp"], 3);
  EXPECT_FALSE(doc["output"].contains("preview"));
  EXPECT_EQ(doc["scene"]["objects"][0]["file"], "assets/cornell_box.obj");
  EXPECT_EQ(s.job.render.width, 64);
  // What the scheduler will parse is what was parsed here.
  const Job reparsed = parse_job(s.spec.job_json(), kSource / "jobs/cornell.json");
  EXPECT_EQ(reparsed.render.engine, EngineKind::Path);
}

TEST(JobSubmission, ModelsOutsideTheJobFolderArePathsUnderTheAssetRoot) {
  // The lab's cow job names ../../shared/assets/dae/cow.dae; sent with that folder as the root.
  JobLoadOptions load;
  load.asset_root = FARM_SHARED_ASSETS;
  const JobSubmission s = make_job_submission(kSource / "jobs/cow.json", load, {});
  EXPECT_EQ(asset_paths(s.spec), (std::vector<std::string>{"dae/cow.dae"}));
  EXPECT_EQ(nlohmann::json::parse(s.spec.job_json())["scene"]["objects"][0]["file"], "dae/cow.dae");
}

TEST(JobSubmission, AJobWithoutARenderBlockSentFromAnotherRootStillHasNone) {
  // Rewritten for its model paths only: no "render": null appears (the scheduler refuses one).
  TempDir dir;
  fs::create_directories(dir / "assets");
  fs::copy_file(kSource / "jobs/assets/cornell_box.obj", dir / "assets/box.obj");
  fs::copy_file(kSource / "jobs/assets/cornell_box.mtl", dir / "assets/cornell_box.mtl");
  const fs::path job = dir.write("jobs/plain.json", R"({"version": 1, "scene": {"objects": [{"file": "../assets/box.obj"}]}})");
  JobLoadOptions load;
  load.asset_root = dir / "assets";
  const JobSubmission s = make_job_submission(job, load, {});
  const auto doc = nlohmann::json::parse(s.spec.job_json());
  EXPECT_FALSE(doc.contains("render")) << s.spec.job_json();
  EXPECT_EQ(doc["scene"]["objects"][0]["file"], "box.obj");
  parse_job(s.spec.job_json(), dir / "assets" / "plain.json");  // laid out as the scheduler does: no InputError
}

TEST(JobSubmission, AReferenceOutsideTheAssetRootIsRefusedNamingBoth) {
  TempDir dir;
  fs::create_directories(dir / "job");
  std::ofstream(dir / "outside.mtl") << "newmtl m\nKd 1 0 0\n";
  std::ofstream(dir / "job/m.obj") << "mtllib ../outside.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n";
  const fs::path job = dir.write("job/j.json", R"({"version": 1, "scene": {"objects": [{"file": "m.obj"}]}})");
  try {
    make_job_submission(job, {}, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.obj"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("outside the asset root"), std::string::npos) << e.what();
  }
}

TEST(JobSubmission, AColladaImageOutsideTheAssetRootIsRefusedAsAPathOrAFileUri) {
  TempDir dir;
  fs::create_directories(dir / "job");
  std::ofstream(dir / "outside.png") << "png";
  const fs::path job = dir.write("job/j.json", R"({"version": 1, "scene": {"objects": [{"file": "m.dae"}]}})");
  std::ofstream(dir / "job/m.dae") << "<COLLADA><library_images><image id=\"i\"><init_from>../outside.png"
                                      "</init_from></image></library_images></COLLADA>";
  expect_outside_root_error(job, "m.dae");
  std::ofstream(dir / "job/m.dae") << "<COLLADA><library_images><image id=\"i\"><init_from><ref>file://"
                                   << (dir / "outside.png").generic_string()
                                   << "</ref></init_from></image></library_images></COLLADA>";
  expect_outside_root_error(job, "m.dae", "is an absolute path");
}

TEST(JobSubmission, AHundredObjectsOfOneModelReadItsReferencesOnceAndHashEachFileOnce) {
  TempDir dir;
  std::ofstream(dir / "skin.png") << "png";
  std::ofstream(dir / "cow.dae") << "<COLLADA><library_images><image id=\"i\"><init_from>skin.png</init_from>"
                                    "</image></library_images></COLLADA>";
  const fs::path job = dir.write("j.json", job_of_copies({"cow.dae"}, 100));
  const JobSubmission s = make_job_submission(job, {}, {});
  EXPECT_EQ(s.job.scene.objects.size(), 100u);
  EXPECT_EQ(asset_paths(s.spec), (std::vector<std::string>{"cow.dae", "skin.png"}));
  EXPECT_EQ(s.files_scanned, 1u);
  EXPECT_EQ(s.files_hashed, 2u);
}

TEST(JobSubmission, AMalformedColladaModelGoesWithoutReferencesForItsLoaderToReport) {
  TempDir dir;
  std::ofstream(dir / "skin.png") << "png";
  std::ofstream(dir / "m.dae") << "<COLLADA><library_images><image id=\"i\"><init_from>skin.png</init_from>";
  const JobSubmission s = make_job_submission(dir.write("j.json", job_of_copies({"m.dae"}, 1)), {}, {});
  EXPECT_EQ(asset_paths(s.spec), std::vector<std::string>{"m.dae"});
}

}  // namespace
}  // namespace farm
