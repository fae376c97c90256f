// What `farm submit` (and the embedded farm) send: the job text and every file it reads.
#include "server/client/job_submission.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "renderer/scene/input_error.h"
#include "server/client/model_dependencies.h"
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

TEST(ModelDependencies, ObjMaterialLibrariesAndTheirMapsThatExist) {
  TempDir dir;
  std::ofstream(dir / "a.mtl") << "newmtl m\nKd 1 1 1\nmap_Kd -s 1 1 1 tex/wood.png\nmap_Ks missing.png\n";
  std::ofstream(dir / "b.mtl") << "newmtl n\n";
  fs::create_directories(dir / "tex");
  std::ofstream(dir / "tex/wood.png") << "png";
  std::ofstream(dir / "m.obj") << "mtllib a.mtl b.mtl\nv 0 0 0\n";
  const auto deps = model_dependencies(dir / "m.obj");
  const std::vector<fs::path> expected{(dir / "a.mtl").lexically_normal(), (dir / "b.mtl").lexically_normal(),
                                       (dir / "tex/wood.png").lexically_normal()};
  EXPECT_EQ(deps, expected);
}

TEST(ModelDependencies, GltfExternalBuffersAndImagesButNotDataUris) {
  TempDir dir;
  std::ofstream(dir / "mesh data.bin") << "bin";
  std::ofstream(dir / "albedo.png") << "png";
  std::ofstream(dir / "m.gltf") << R"({"asset": {"version": "2.0"},
      "buffers": [{"uri": "mesh%20data.bin", "byteLength": 3}, {"uri": "data:application/octet-stream;base64,AAAA"}],
      "images": [{"uri": "albedo.png"}, {"uri": "https://example.com/x.png"}]})";
  const auto deps = model_dependencies(dir / "m.gltf");
  const std::vector<fs::path> expected{(dir / "albedo.png").lexically_normal(), (dir / "mesh data.bin").lexically_normal()};
  EXPECT_EQ(deps, expected);
  // The test GLB embeds everything.
  EXPECT_TRUE(model_dependencies(fs::path(FARM_TEST_DATA) / "quad_scene.glb").empty());
}

TEST(ModelDependencies, ColladaImages) {
  TempDir dir;
  std::ofstream(dir / "skin.png") << "png";
  std::ofstream(dir / "m.dae") << "<COLLADA><library_images><image id=\"i\"><init_from>skin.png</init_from></image>"
                                  "</library_images><surface><init_from>i</init_from></surface></COLLADA>";
  EXPECT_EQ(model_dependencies(dir / "m.dae"), std::vector<fs::path>{(dir / "skin.png").lexically_normal()});
  EXPECT_TRUE(model_dependencies(fs::path(FARM_SHARED_ASSETS) / "dae/cow.dae").empty());
}

}  // namespace
}  // namespace farm
