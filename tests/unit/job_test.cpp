#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "renderer/job/job.h"
#include "renderer/util/confined_file.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

// A private folder per test:
//   jobs/                 the job folder and default asset root
//     assets/cow.dae, assets/teapot.obj
//     assets/inside.dae   -> cow.dae             (symlink that stays inside)
//     assets/escape.dae   -> ../../outside/secret.dae (symlink that leaves)
//   jobs2/cow.dae         a sibling whose name shares the prefix "jobs"
//   outside/secret.dae
class JobFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(root_ / "jobs" / "assets");
    fs::create_directories(root_ / "jobs2");
    fs::create_directories(root_ / "outside");
    touch(root_ / "jobs" / "assets" / "cow.dae");
    touch(root_ / "jobs" / "assets" / "teapot.obj");
    touch(root_ / "jobs2" / "cow.dae");
    touch(root_ / "outside" / "secret.dae");
    fs::create_symlink("cow.dae", root_ / "jobs" / "assets" / "inside.dae");
    fs::create_symlink(root_ / "outside" / "secret.dae", root_ / "jobs" / "assets" / "escape.dae");
  }
  static void touch(const fs::path& p) { std::ofstream(p) << "not loaded by the job parser\n"; }

  fs::path job_path() const { return root_ / "jobs" / "job.json"; }
  fs::path asset(const std::string& name) const {
    return fs::canonical(root_ / "jobs" / "assets" / name);
  }

  Job parse(const std::string& text, const JobLoadOptions& options = {}) const {
    return parse_job(text, job_path(), options);
  }

  // The InputError message `text` produces, or a test failure when it parses.
  std::string error_of(const std::string& text, const JobLoadOptions& options = {}) const {
    try {
      parse(text, options);
    } catch (const InputError& e) {
      return e.what();
    }
    ADD_FAILURE() << "expected an InputError for:\n" << text;
    return {};
  }

  test::TempDir temp_;
  fs::path root_ = temp_.path();
};

std::string job_with_object(const std::string& object) {
  return R"({"version": 1, "scene": {"objects": [)" + object + "]}}";
}
std::string job_with_scene_keys(const std::string& keys) {
  return R"({"version": 1, "scene": {"objects": [{"file": "assets/cow.dae"}], )" + keys + "}}";
}
std::string job_with_keys(const std::string& keys) {
  return R"({"version": 1, "scene": {"objects": [{"file": "assets/cow.dae"}]}, )" + keys + "}";
}
std::string object_with(const std::string& keys) {
  return job_with_object(R"({"file": "assets/cow.dae", )" + keys + "}");
}

bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// ---- valid jobs ----------------------------------------------------------------------------

// Worker requirements (issue #36): tags sorted and each once, a thread minimum; none by default;
// each bad value named by its place.
TEST_F(JobFiles, RequirementsAreReadAndCheckedWhereTheyStand) {
  EXPECT_TRUE(parse(job_with_keys(R"("name": "plain")")).requirements.empty());
  const Job job = parse(job_with_keys(R"("requirements": {"tags": ["gpu", "big-mem", "gpu"], "min_threads": 8})"));
  EXPECT_EQ(job.requirements.tags, (std::vector<std::string>{"big-mem", "gpu"}));
  EXPECT_EQ(job.requirements.min_threads, 8);
  EXPECT_TRUE(job.requirements.met_by({"a", "big-mem", "gpu"}, 8));
  EXPECT_FALSE(job.requirements.met_by({"big-mem", "gpu"}, 7));
  EXPECT_FALSE(job.requirements.met_by({"gpu"}, 16));
  EXPECT_EQ(job.requirements.lacking({"gpu"}, 0), "the tag big-mem and 8 threads (it did not say how many it has)");
  EXPECT_EQ(job.requirements.describe(), "the tags big-mem, gpu and 8 threads");

  const std::string bad_tag = error_of(job_with_keys(R"("requirements": {"tags": ["ok", "no spaces"]})"));
  EXPECT_TRUE(contains(bad_tag, "requirements.tags[1]")) << bad_tag;
  EXPECT_TRUE(contains(bad_tag, "letters, digits")) << bad_tag;
  const std::string threads = error_of(job_with_keys(R"("requirements": {"min_threads": 5000})"));
  EXPECT_TRUE(contains(threads, "requirements.min_threads")) << threads;
  const std::string unknown = error_of(job_with_keys(R"("requirements": {"memory": 64})"));
  EXPECT_TRUE(contains(unknown, "memory")) << unknown;
  std::string many = R"("requirements": {"tags": [)";
  for (int i = 0; i < 17; ++i) many += (i ? ", " : "") + std::string("\"t") + std::to_string(i) + "\"";
  const std::string too_many = error_of(job_with_keys(many + "]}"));
  EXPECT_TRUE(contains(too_many, "17 tags; at most 16")) << too_many;
}

TEST_F(JobFiles, JobParse_FullJobKeepsEveryField) {
  const Job job = parse(R"({
    "version": 1,
    "name": "cow-test",
    "scene": {
      "objects": [
        { "file": "assets/cow.dae",
          "translate": [1, 2, 3], "rotate": {"axis": [0, 0, 2], "degrees": 90},
          "scale": [2, 0.5, -1],
          "material": { "ambient": [0.1, 0.2, 0.3], "diffuse": [0.8, 0.6, 0.4],
                        "specular": [0.5, 0.5, 0.5], "emission": [1, 2, 3],
                        "shininess": 32, "ior": 1.5, "transmission": 0.25,
                        "emission_sides": "both" } },
        { "file": "assets/teapot.obj" }
      ],
      "camera": { "position": [2, 3, 4], "target": [0, 1, 0], "up": [0, 0, 1], "fov_y": 60,
                  "near": 0.5, "far": 50, "aspect": 1.5 },
      "lights": [ { "position": [2, 2, 2], "intensity": 7 },
                  { "position": [-1, 4, 0], "intensity": [1, 2, 3] } ],
      "ambient": [0.2, 0.2, 0.2],
      "background": [0, 0.5, 1]
    },
    "render": { "engine": "path", "width": 320, "height": 240, "spp": 16, "max_depth": -1,
                "seed": 42, "tile_size": 16, "threads": 3, "accel": "bvh-median" },
    "output": { "image": "renders/cow.exr", "preview": "renders/cow.jpg",
                "aovs": ["depth", "normal", "albedo", "bvh_cost", "variance"] },
    "validate": { "embree_rays": 4096 }
  })");

  EXPECT_EQ(job.path, job_path());
  EXPECT_EQ(job.name, "cow-test");

  ASSERT_EQ(job.scene.objects.size(), 2u);
  const JobObject& cow = job.scene.objects[0];
  EXPECT_EQ(cow.file, asset("cow.dae"));
  EXPECT_TRUE(cow.file.is_absolute());
  EXPECT_EQ(cow.file_as_written, "assets/cow.dae");
  EXPECT_EQ(cow.transform.translate, glm::vec3(1, 2, 3));
  EXPECT_EQ(cow.transform.rotate_axis, glm::vec3(0, 0, 1));  // stored normalised
  EXPECT_EQ(cow.transform.rotate_degrees, 90.0f);
  EXPECT_EQ(cow.transform.scale, glm::vec3(2, 0.5f, -1));
  ASSERT_TRUE(cow.material.ambient && cow.material.diffuse && cow.material.specular &&
              cow.material.emission && cow.material.shininess && cow.material.ior &&
              cow.material.transmission && cow.material.emission_sides);
  EXPECT_EQ(*cow.material.ambient, glm::vec3(0.1f, 0.2f, 0.3f));
  EXPECT_EQ(*cow.material.diffuse, glm::vec3(0.8f, 0.6f, 0.4f));
  EXPECT_EQ(*cow.material.specular, glm::vec3(0.5f));
  EXPECT_EQ(*cow.material.emission, glm::vec3(1, 2, 3));
  EXPECT_EQ(*cow.material.shininess, 32.0f);
  EXPECT_EQ(*cow.material.ior, 1.5f);
  EXPECT_EQ(*cow.material.transmission, 0.25f);
  EXPECT_EQ(*cow.material.emission_sides, EmissionSides::Both);

  const JobObject& teapot = job.scene.objects[1];
  EXPECT_EQ(teapot.file, asset("teapot.obj"));
  EXPECT_EQ(teapot.transform.scale, glm::vec3(1));
  EXPECT_TRUE(teapot.material.empty());

  ASSERT_TRUE(job.scene.camera);
  const Camera& cam = *job.scene.camera;
  EXPECT_EQ(cam.position, glm::vec3(2, 3, 4));
  EXPECT_EQ(cam.target, glm::vec3(0, 1, 0));
  EXPECT_EQ(cam.up, glm::vec3(0, 0, 1));
  EXPECT_EQ(cam.fov_y_degrees, 60.0f);
  EXPECT_EQ(cam.near, 0.5f);
  EXPECT_EQ(cam.far, 50.0f);
  ASSERT_TRUE(cam.aspect);
  EXPECT_EQ(*cam.aspect, 1.5f);

  ASSERT_TRUE(job.scene.lights);
  ASSERT_EQ(job.scene.lights->size(), 2u);
  EXPECT_EQ((*job.scene.lights)[0].kind, Light::Kind::Point);
  EXPECT_EQ((*job.scene.lights)[0].position, glm::vec3(2, 2, 2));
  EXPECT_EQ((*job.scene.lights)[0].intensity, glm::vec3(7));
  EXPECT_EQ((*job.scene.lights)[1].position, glm::vec3(-1, 4, 0));
  EXPECT_EQ((*job.scene.lights)[1].intensity, glm::vec3(1, 2, 3));
  EXPECT_EQ(job.scene.ambient, glm::vec3(0.2f));
  EXPECT_EQ(job.scene.background, glm::vec3(0, 0.5f, 1));

  EXPECT_EQ(job.render.engine, EngineKind::Path);
  EXPECT_EQ(job.render.width, 320);
  EXPECT_EQ(job.render.height, 240);
  EXPECT_EQ(job.render.spp, 16);
  EXPECT_EQ(job.render.max_depth, -1);
  EXPECT_EQ(job.render.seed, 42u);
  EXPECT_EQ(job.render.tile_size, 16);
  EXPECT_EQ(job.render.threads, 3);
  EXPECT_EQ(job.render.accel, AccelKind::BvhMedian);
  EXPECT_TRUE(job.render.aovs.depth && job.render.aovs.normal && job.render.aovs.albedo &&
              job.render.aovs.bvh_cost && job.render.aovs.variance);

  EXPECT_EQ(job.output.image, fs::path("renders/cow.exr"));
  EXPECT_EQ(job.output.preview, fs::path("renders/cow.jpg"));
  EXPECT_EQ(job.embree_rays, 4096);
}

TEST_F(JobFiles, JobParse_MinimalJobGetsDefaults) {
  const Job job = parse(job_with_object(R"({"file": "assets/cow.dae"})"));
  EXPECT_EQ(job.name, "job");  // the job file's stem
  ASSERT_EQ(job.scene.objects.size(), 1u);
  const ObjectTransform t = job.scene.objects[0].transform;
  EXPECT_EQ(t.translate, glm::vec3(0));
  EXPECT_EQ(t.rotate_axis, glm::vec3(0, 1, 0));
  EXPECT_EQ(t.rotate_degrees, 0.0f);
  EXPECT_EQ(t.scale, glm::vec3(1));
  EXPECT_TRUE(job.scene.objects[0].material.empty());
  EXPECT_FALSE(job.scene.camera);  // the models' camera, else the default, is picked later
  EXPECT_FALSE(job.scene.lights);
  EXPECT_EQ(job.scene.ambient, glm::vec3(0.1f));
  EXPECT_EQ(job.scene.background, glm::vec3(100.0f / 255.0f));

  const RenderSettings defaults;
  EXPECT_EQ(job.render.engine, EngineKind::Raster);
  EXPECT_EQ(job.render.width, 640);
  EXPECT_EQ(job.render.height, 480);
  EXPECT_EQ(job.render.spp, 1);
  EXPECT_EQ(job.render.max_depth, 5);
  EXPECT_EQ(job.render.seed, 0u);
  EXPECT_EQ(job.render.tile_size, 32);
  EXPECT_EQ(job.render.threads, 0);
  EXPECT_EQ(job.render.accel, AccelKind::Bvh);
  EXPECT_FALSE(job.render.aovs.depth || job.render.aovs.normal || job.render.aovs.albedo ||
               job.render.aovs.bvh_cost || job.render.aovs.variance);
  EXPECT_EQ(job.output.image, fs::path("out/job.exr"));
  EXPECT_EQ(job.output.preview, fs::path("out/job.png"));
  EXPECT_EQ(job.embree_rays, 0);
}

TEST_F(JobFiles, JobParse_DefaultOutputPathsUseTheGivenName) {
  const Job job = parse(job_with_keys(R"("name": "teapot_v2")"));
  EXPECT_EQ(job.output.image, fs::path("out/teapot_v2.exr"));
  EXPECT_EQ(job.output.preview, fs::path("out/teapot_v2.png"));
}

TEST_F(JobFiles, JobParse_OutputPathsAreKeptAsWritten) {
  const Job job = parse(job_with_keys(
      R"("output": {"image": "../renders/./a.exr", "preview": "/tmp/farm-preview.png"})"));
  EXPECT_EQ(job.output.image, fs::path("../renders/./a.exr"));
  EXPECT_EQ(job.output.preview, fs::path("/tmp/farm-preview.png"));
}

TEST_F(JobFiles, JobParse_EmptyPreviewMeansNone) {
  const Job job = parse(job_with_keys(R"("output": {"preview": ""})"));
  EXPECT_TRUE(job.output.preview.empty());
  EXPECT_EQ(job.output.image, fs::path("out/job.exr"));
}

TEST_F(JobFiles, JobParse_PartialCameraKeepsDefaultsForOtherKeys) {
  const Job job = parse(job_with_scene_keys(R"("camera": {"position": [0, 0, 8]})"));
  ASSERT_TRUE(job.scene.camera);
  const Camera defaults;
  EXPECT_EQ(job.scene.camera->position, glm::vec3(0, 0, 8));
  EXPECT_EQ(job.scene.camera->target, defaults.target);
  EXPECT_EQ(job.scene.camera->up, defaults.up);
  EXPECT_EQ(job.scene.camera->fov_y_degrees, 45.0f);
  EXPECT_EQ(job.scene.camera->near, 0.1f);
  EXPECT_EQ(job.scene.camera->far, 10.0f);
  EXPECT_FALSE(job.scene.camera->aspect);
}

TEST_F(JobFiles, JobParse_LightIntensityDefaultsToTenAndScalarBecomesGrey) {
  const Job job = parse(job_with_scene_keys(
      R"("lights": [{"position": [0, 3, 0]}, {"position": [1, 1, 1], "intensity": 2.5}])"));
  ASSERT_TRUE(job.scene.lights);
  ASSERT_EQ(job.scene.lights->size(), 2u);
  EXPECT_EQ((*job.scene.lights)[0].intensity, glm::vec3(10));
  EXPECT_EQ((*job.scene.lights)[1].intensity, glm::vec3(2.5f));
}

TEST_F(JobFiles, JobParse_EmptyLightListIsKeptSoModelLightsAreNotUsed) {
  const Job job = parse(job_with_scene_keys(R"("lights": [])"));
  ASSERT_TRUE(job.scene.lights);
  EXPECT_TRUE(job.scene.lights->empty());
}

TEST_F(JobFiles, JobParse_IntegralFloatIsAcceptedWhereAnIntegerIsExpected) {
  const Job job = parse(job_with_keys(R"("render": {"width": 640.0, "height": 1e3})"));
  EXPECT_EQ(job.render.width, 640);
  EXPECT_EQ(job.render.height, 1000);
}

TEST_F(JobFiles, JobParse_SeedTakesTheFullUnsignedRange) {
  const Job job = parse(job_with_keys(R"("render": {"seed": 18446744073709551615})"));
  EXPECT_EQ(job.render.seed, 18446744073709551615u);
}

TEST_F(JobFiles, JobParse_BoundaryValuesAreAccepted) {
  const Job job = parse(job_with_keys(
      R"("render": {"width": 16384, "height": 1, "max_depth": -1, "threads": 0, "spp": 1})"));
  EXPECT_EQ(job.render.width, 16384);
  EXPECT_EQ(job.render.height, 1);
  EXPECT_EQ(job.render.max_depth, -1);
  const Job upper = parse(job_with_keys(
      R"("render": {"spp": 1048576, "tile_size": 16384, "threads": 1024})"));
  EXPECT_EQ(upper.render.spp, 1048576);
  EXPECT_EQ(upper.render.tile_size, 16384);
  EXPECT_EQ(upper.render.threads, 1024);
}

TEST_F(JobFiles, JobParse_EnvironmentKeepsItsMapRadianceIntensityAndTurn) {
  const Job job = parse(job_with_scene_keys(
      R"("environment": {"map": "assets/teapot.obj", "radiance": [1, 0.5, 0.25], "intensity": 3, "rotate_degrees": -90})"));
  ASSERT_TRUE(job.scene.environment.has_value());
  const JobEnvironment& e = *job.scene.environment;
  EXPECT_EQ(e.map, asset("teapot.obj"));
  EXPECT_EQ(e.map_as_written, "assets/teapot.obj");
  EXPECT_EQ(e.radiance, glm::vec3(1.0f, 0.5f, 0.25f));
  EXPECT_EQ(e.intensity, 3.0f);
  EXPECT_EQ(e.rotate_degrees, -90.0f);
  EXPECT_EQ(job_named_files(job), (std::vector<fs::path>{asset("cow.dae"), asset("teapot.obj")}));
  // A constant one: no map, the radiance grey from one number.
  const Job constant = parse(job_with_scene_keys(R"("environment": {"radiance": 0.5})"));
  EXPECT_TRUE(constant.scene.environment->map.empty());
  EXPECT_EQ(constant.scene.environment->radiance, glm::vec3(0.5f));
  EXPECT_EQ(job_named_files(constant), (std::vector<fs::path>{asset("cow.dae")}));
  EXPECT_FALSE(parse(job_with_scene_keys(R"("background": [0, 0, 0])")).scene.environment.has_value());
}

TEST_F(JobFiles, JobParse_RepeatedFileGivesOneObjectPerEntry) {
  const Job job = parse(job_with_object(
      R"({"file": "assets/cow.dae"}, {"file": "./assets/../assets/cow.dae", "translate": [3, 0, 0]})"));
  ASSERT_EQ(job.scene.objects.size(), 2u);
  EXPECT_EQ(job.scene.objects[0].file, job.scene.objects[1].file);  // canonical, so shareable
  EXPECT_EQ(job.scene.objects[1].file_as_written, "./assets/../assets/cow.dae");
}

// ---- paths ---------------------------------------------------------------------------------

TEST_F(JobFiles, JobPaths_SymlinkInsideRootIsAcceptedAndStoredCanonical) {
  const Job job = parse(job_with_object(R"({"file": "assets/inside.dae"})"));
  EXPECT_EQ(job.scene.objects[0].file, asset("cow.dae"));
  EXPECT_EQ(job.scene.objects[0].file_as_written, "assets/inside.dae");
}

// A scene places one model under many objects: each name is resolved once a parse (each
// resolution walks the name's folders with a syscall apiece; 10,000 cows spent half their set-up
// there), and every object still gets its own name's verdict: a link inside the root, the same
// file by another spelling, and a link out of the root refused where it stands.
TEST_F(JobFiles, JobPaths_EachNameIsResolvedOnceHoweverManyObjectsNameIt) {
  std::string objects;
  for (int i = 0; i < 50; ++i) {
    objects += R"({"file": "assets/cow.dae"}, {"file": "assets/inside.dae"}, {"file": "./assets/cow.dae"}, )";
  }
  const std::uint64_t before = confine_file_calls();
  const Job job = parse(job_with_object(objects + R"({"file": "assets/teapot.obj"})"));
  EXPECT_EQ(confine_file_calls() - before, 4u);
  ASSERT_EQ(job.scene.objects.size(), 151u);
  for (std::size_t i = 0; i < 150; ++i) {
    EXPECT_EQ(job.scene.objects[i].file, asset("cow.dae")) << i;
  }
  EXPECT_EQ(job.scene.objects[1].file_as_written, "assets/inside.dae");
  EXPECT_EQ(job.scene.objects[150].file, asset("teapot.obj"));
  // What a submission uploads besides the models' own files: each file once.
  EXPECT_EQ(job_named_files(job), (std::vector<fs::path>{asset("cow.dae"), asset("teapot.obj")}));

  const std::string msg = error_of(job_with_object(objects + R"({"file": "assets/escape.dae"})"));
  EXPECT_TRUE(contains(msg, "scene.objects[150].file: 'assets/escape.dae'")) << msg;
}

TEST_F(JobFiles, JobPaths_AbsolutePathInsideRootIsAccepted) {
  const std::string abs = (root_ / "jobs" / "assets" / "cow.dae").string();
  const Job job = parse(job_with_object(R"({"file": ")" + abs + R"("})"));
  EXPECT_EQ(job.scene.objects[0].file, asset("cow.dae"));
}

TEST_F(JobFiles, JobPaths_AssetRootOptionAllowsFilesBesideTheJobFolder) {
  JobLoadOptions options;
  options.asset_root = root_;
  const Job job = parse(job_with_object(R"({"file": "../jobs2/cow.dae"})"), options);
  EXPECT_EQ(job.scene.objects[0].file, fs::canonical(root_ / "jobs2" / "cow.dae"));
}

TEST_F(JobFiles, JobPaths_AssetRootOptionNarrowerThanJobFolderIsEnforced) {
  JobLoadOptions options;
  options.asset_root = root_ / "jobs" / "assets";
  EXPECT_NO_THROW(parse(job_with_object(R"({"file": "assets/cow.dae"})"), options));
  const std::string msg = error_of(job_with_object(R"({"file": "job.json"})"), options);
  EXPECT_TRUE(contains(msg, "scene.objects[0].file: 'job.json' lies outside the asset root"))
      << msg;
}

// ---- errors --------------------------------------------------------------------------------

TEST_F(JobFiles, JobErrors_SyntaxErrorGivesLineAndColumn) {
  const std::string text = "{\n  \"version\": 1,\n    \"scene\": x\n}\n";
  const std::string msg = error_of(text);
  EXPECT_EQ(msg.rfind(job_path().string() + ":3:14: JSON syntax error: ", 0), 0u) << msg;
}

TEST_F(JobFiles, JobErrors_SyntaxErrorAtEndOfInputGivesItsPlace) {
  const std::string msg = error_of("{\"version\": 1");
  EXPECT_EQ(msg.rfind(job_path().string() + ":1:14: JSON syntax error: ", 0), 0u) << msg;
  const std::string empty = error_of("");
  EXPECT_EQ(empty.rfind(job_path().string() + ":1:1: JSON syntax error: ", 0), 0u) << empty;
}

TEST_F(JobFiles, JobErrors_TrailingGarbageIsASyntaxError) {
  const std::string msg = error_of(job_with_object(R"({"file": "assets/cow.dae"})") + "\n  }");
  EXPECT_EQ(msg.rfind(job_path().string() + ":2:3: JSON syntax error: ", 0), 0u) << msg;
}

TEST_F(JobFiles, JobErrors_TopLevelMustBeAnObject) {
  const std::string msg = error_of("[1, 2]");
  EXPECT_EQ(msg, job_path().string() + ": expected an object, got an array of 2");
}

TEST_F(JobFiles, JobErrors_DeeplyNestedInputFailsCleanly) {
  const std::size_t depth = 200000;
  const std::string text = R"({"version": 1, "scene": {"objects": [)" + std::string(depth, '[') +
                           std::string(depth, ']') + "]}}";
  const std::string msg = error_of(text);
  EXPECT_EQ(msg, job_path().string() + ": scene.objects[0]: expected an object, got an array of 1");
}

TEST_F(JobFiles, JobLoad_ReadsTheJobFileFromDisk) {
  std::ofstream(job_path()) << job_with_keys(R"("render": {"width": 64, "height": 32})");
  const Job job = load_job(job_path());
  EXPECT_EQ(job.path, job_path());
  EXPECT_EQ(job.render.width, 64);
  EXPECT_EQ(job.scene.objects[0].file, asset("cow.dae"));
}

TEST_F(JobFiles, JobLoad_MissingJobFileIsAnInputErrorNamingIt) {
  const fs::path missing = root_ / "jobs" / "nope.json";
  try {
    load_job(missing);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), missing.string() + ": no such job file");
  }
}

TEST_F(JobFiles, JobLoad_DirectoryIsNotAJobFile) {
  EXPECT_THROW(load_job(root_ / "jobs"), InputError);
}

// Each bad job must fail with "<job file>: <json path>: ..." and the message fragment given.
struct BadJob {
  std::string name;
  std::string text;  // "{OUTSIDE}" is replaced by the absolute path of the outside folder
  std::string path;
  std::string fragment;
};

void PrintTo(const BadJob& bad, std::ostream* os) { *os << bad.name; }

class JobValidation : public JobFiles, public ::testing::WithParamInterface<BadJob> {};

TEST_P(JobValidation, FailsNamingFileAndJsonPath) {
  const BadJob& bad = GetParam();
  std::string text = bad.text;
  const std::string placeholder = "{OUTSIDE}";
  if (const auto at = text.find(placeholder); at != std::string::npos) {
    text.replace(at, placeholder.size(), (root_ / "outside").string());
  }
  const std::string msg = error_of(text);
  const std::string prefix = job_path().string() + ": " + bad.path + ": ";
  EXPECT_EQ(msg.rfind(prefix, 0), 0u) << "message: " << msg << "\nexpected prefix: " << prefix;
  EXPECT_TRUE(contains(msg, bad.fragment)) << "message: " << msg << "\nexpected: " << bad.fragment;
}

const std::vector<BadJob> kBadJobs = {
    // keys
    {"UnknownTopLevelKey", job_with_keys(R"("colour": 1)"), "colour", "unknown key (expected version, name"},
    {"UnknownNestedKey", job_with_scene_keys(R"("camera": {"fov_y": 45, "foo": 1})"),
     "scene.camera.foo", "unknown key"},
    {"UnknownKeyInObject", object_with(R"("rotation": [0, 1, 0])"), "scene.objects[0].rotation",
     "unknown key"},
    {"UnknownKeyThatIsNotAnIdentifier", job_with_keys(R"("my key": 1)"), R"(["my key"])",
     "unknown key"},
    {"DuplicateKey", job_with_keys(R"("render": {"width": 10, "width": 20})"), "render.width",
     "duplicate key"},
    {"MissingScene", R"({"version": 1})", "scene", "required key is missing"},
    {"MissingObjects", R"({"version": 1, "scene": {}})", "scene.objects", "required key is missing"},
    {"EmptyObjects", R"({"version": 1, "scene": {"objects": []}})", "scene.objects",
     "at least one object"},
    {"ObjectWithoutFile", job_with_object(R"({"translate": [0, 0, 0]})"), "scene.objects[0].file",
     "required key is missing"},
    {"LightWithoutPosition", job_with_scene_keys(R"("lights": [{"intensity": 3}])"),
     "scene.lights[0].position", "required key is missing"},
    // version
    {"VersionTwo", R"({"version": 2, "scene": {"objects": [{"file": "assets/cow.dae"}]}})", "version",
     "unsupported version 2"},
    {"VersionTwoIsReportedBeforeItsUnknownKeys",
     R"({"version": 2, "scene": {"objects": [{"file": "assets/cow.dae"}]}, "future": 1})", "version",
     "unsupported version 2"},
    {"MissingVersion", R"({"scene": {"objects": [{"file": "assets/cow.dae"}]}})", "version",
     "required key is missing"},
    {"VersionAsString", R"({"version": "1", "scene": {"objects": [{"file": "assets/cow.dae"}]}})",
     "version", "expected an integer, got a string (\"1\")"},
    // types
    {"StringWhereIntegerExpected", job_with_keys(R"("render": {"width": "640"})"), "render.width",
     "expected an integer, got a string (\"640\")"},
    {"BooleanWhereIntegerExpected", job_with_keys(R"("render": {"spp": true})"), "render.spp",
     "expected an integer, got a boolean (true)"},
    {"BooleanWhereNumberExpected", object_with(R"("translate": [true, 0, 0])"),
     "scene.objects[0].translate[0]", "expected a number, got a boolean (true)"},
    {"NullWhereNumberExpected", job_with_scene_keys(R"("camera": {"fov_y": null})"),
     "scene.camera.fov_y", "expected a number, got null"},
    {"NonIntegerWidth", job_with_keys(R"("render": {"width": 640.5})"), "render.width",
     "expected an integer, got 640.5"},
    {"ObjectsNotAnArray", R"({"version": 1, "scene": {"objects": {"file": "assets/cow.dae"}}})",
     "scene.objects", "expected an array, got an object"},
    {"ObjectEntryNotAnObject", job_with_object("5"), "scene.objects[0]", "expected an object, got 5"},
    {"FileNotAString", job_with_object(R"({"file": 3})"), "scene.objects[0].file",
     "expected a string, got 3"},
    {"LightIntensityString", job_with_scene_keys(R"("lights": [{"position": [0, 1, 0], "intensity": "hi"}])"),
     "scene.lights[0].intensity", "expected a number or 3 numbers"},
    // numbers
    {"NumberOverflowingDouble", object_with(R"("translate": [1e999, 0, 0])"),
     "scene.objects[0].translate[0]", "out of range"},
    {"NegativeNumberOverflowingDouble", job_with_scene_keys(R"("camera": {"near": -1e400})"),
     "scene.camera.near", "out of range"},
    {"NumberOverflowingFloat", job_with_scene_keys(R"("ambient": [1e39, 0, 0])"), "scene.ambient[0]",
     "out of range for a 32-bit float"},
    // environment
    {"EnvironmentBesideBackground", job_with_scene_keys(R"("background": [0, 0, 0], "environment": {})"),
     "scene.environment", "an environment stands for scene.background too"},
    {"EnvironmentBesideAmbient", job_with_scene_keys(R"("ambient": [0, 0, 0], "environment": {"radiance": 1})"),
     "scene.environment", "an environment stands for scene.ambient too"},
    {"EnvironmentMapMissing", job_with_scene_keys(R"("environment": {"map": "assets/sky.hdr"})"),
     "scene.environment.map", "no such file 'assets/sky.hdr'"},
    {"EnvironmentMapOutsideTheRoot", job_with_scene_keys(R"("environment": {"map": "../outside/secret.dae"})"),
     "scene.environment.map", "outside"},
    {"EnvironmentNegativeIntensity", job_with_scene_keys(R"("environment": {"intensity": -1})"),
     "scene.environment.intensity", ">= 0"},
    {"EnvironmentUnknownKey", job_with_scene_keys(R"("environment": {"rotate": 10})"),
     "scene.environment.rotate", "unknown key"},
    {"NegativeWidth", job_with_keys(R"("render": {"width": -5})"), "render.width",
     "expected an integer >= 1, got -5"},
    {"ZeroHeight", job_with_keys(R"("render": {"height": 0})"), "render.height",
     "expected an integer >= 1, got 0"},
    {"WidthAboveLimit", job_with_keys(R"("render": {"width": 16385})"), "render.width",
     "expected an integer <= 16384, got 16385"},
    {"HugeIntegerWidth", job_with_keys(R"("render": {"width": 99999999999999999999999})"),
     "render.width", "expected an integer <= 16384"},
    {"ZeroSpp", job_with_keys(R"("render": {"spp": 0})"), "render.spp", ">= 1"},
    {"SppAboveLimit", job_with_keys(R"("render": {"spp": 1048577})"), "render.spp",
     "expected an integer <= 1048576, got 1048577"},
    {"MaxDepthBelowMinusOne", job_with_keys(R"("render": {"max_depth": -2})"), "render.max_depth",
     "expected an integer >= -1, got -2"},
    {"NegativeSeed", job_with_keys(R"("render": {"seed": -1})"), "render.seed",
     "expected an unsigned integer, got -1"},
    {"FractionalSeed", job_with_keys(R"("render": {"seed": 1.5})"), "render.seed",
     "expected an unsigned integer"},
    {"ZeroTileSize", job_with_keys(R"("render": {"tile_size": 0})"), "render.tile_size", ">= 1"},
    {"TileSizeAboveLimit", job_with_keys(R"("render": {"tile_size": 16385})"), "render.tile_size",
     "expected an integer <= 16384, got 16385"},
    {"NegativeThreads", job_with_keys(R"("render": {"threads": -1})"), "render.threads", ">= 0"},
    {"ThreadsAboveLimit", job_with_keys(R"("render": {"threads": 1025})"), "render.threads",
     "expected an integer <= 1024, got 1025"},
    {"NegativeEmbreeRays", job_with_keys(R"("validate": {"embree_rays": -3})"),
     "validate.embree_rays", ">= 0"},
    // farm render had no bound: 10^12 rays took 4 GB in 5 s (issue #32)
    {"EmbreeRaysAboveLimit", job_with_keys(R"("validate": {"embree_rays": 1000000000000})"),
     "validate.embree_rays", "expected an integer <= 100000000, got 1000000000000"},
    // enumerations
    {"UnknownEngine", job_with_keys(R"("render": {"engine": "foo"})"), "render.engine",
     "unknown engine 'foo' (expected raster, whitted or path)"},
    {"UnknownAccel", job_with_keys(R"("render": {"accel": "kdtree"})"), "render.accel",
     "unknown accel 'kdtree' (expected bvh, bvh-median, naive or embree)"},
    {"UnknownAov", job_with_keys(R"("output": {"aovs": ["depth", "motion"]})"), "output.aovs[1]",
     "unknown AOV 'motion' (expected depth, normal, albedo, bvh_cost or variance)"},
    {"DuplicateAov", job_with_keys(R"("output": {"aovs": ["depth", "normal", "depth"]})"),
     "output.aovs[2]", "duplicate AOV 'depth'"},
    // objects
    {"ScaleWithTwoNumbers", object_with(R"("scale": [1, 1])"), "scene.objects[0].scale",
     "expected 3 numbers, got an array of 2"},
    {"ScaleOfZero", object_with(R"("scale": [1, 0, 1])"), "scene.objects[0].scale[1]",
     "non-zero scale factor"},
    {"RotateAboutZeroAxis", object_with(R"("rotate": {"axis": [0, 0, 0], "degrees": 30})"),
     "scene.objects[0].rotate.axis", "non-zero axis"},
    {"NegativeDiffuse", object_with(R"("material": {"diffuse": [0.5, 0.5, -0.5]})"),
     "scene.objects[0].material.diffuse[2]", "expected a number >= 0, got -0.5"},
    {"NegativeShininess", object_with(R"("material": {"shininess": -1})"),
     "scene.objects[0].material.shininess", ">= 0"},
    {"ZeroIor", object_with(R"("material": {"ior": 0})"), "scene.objects[0].material.ior", "> 0"},
    {"TransmissionAboveOne", object_with(R"("material": {"transmission": 1.5})"),
     "scene.objects[0].material.transmission", "<= 1"},
    {"UnknownEmissionSides", object_with(R"("material": {"emission_sides": "back"})"),
     "scene.objects[0].material.emission_sides", "unknown emission_sides 'back' (expected front or both)"},
    {"EmissionSidesNotAString", object_with(R"("material": {"emission_sides": true})"),
     "scene.objects[0].material.emission_sides", "expected a string, got a boolean (true)"},
    // camera, lights, colours
    {"CameraPositionEqualsTarget",
     job_with_scene_keys(R"("camera": {"position": [1, 2, 3], "target": [1, 2, 3]})"), "scene.camera",
     "position and target are the same point"},
    {"FovY180", job_with_scene_keys(R"("camera": {"fov_y": 180})"), "scene.camera.fov_y",
     "expected a number < 180, got 180"},
    {"FovYZero", job_with_scene_keys(R"("camera": {"fov_y": 0})"), "scene.camera.fov_y", "> 0"},
    {"FarNotBeyondNear", job_with_scene_keys(R"("camera": {"near": 5, "far": 5})"),
     "scene.camera.far", "expected far > near"},
    {"NearBeyondDefaultFar", job_with_scene_keys(R"("camera": {"near": 20})"), "scene.camera.near",
     "expected near < far"},
    {"ZeroAspect", job_with_scene_keys(R"("camera": {"aspect": 0})"), "scene.camera.aspect", "> 0"},
    {"UpParallelToView", job_with_scene_keys(R"("camera": {"position": [0, 5, 0], "target": [0, 0, 0]})"),
     "scene.camera.up", "parallel to the viewing direction"},
    {"ZeroUp", job_with_scene_keys(R"("camera": {"up": [0, 0, 0]})"), "scene.camera.up",
     "non-zero up vector"},
    {"NegativeLightIntensity",
     job_with_scene_keys(R"("lights": [{"position": [0, 1, 0], "intensity": -1}])"),
     "scene.lights[0].intensity", ">= 0"},
    {"NegativeRgbLightIntensity",
     job_with_scene_keys(R"("lights": [{"position": [0, 1, 0], "intensity": [1, -1, 1]}])"),
     "scene.lights[0].intensity[1]", ">= 0"},
    {"NegativeBackground", job_with_scene_keys(R"("background": [0, -0.1, 0])"),
     "scene.background[1]", ">= 0"},
    // files
    {"MissingModelFile", job_with_object(R"({"file": "assets/x.dae"})"), "scene.objects[0].file",
     "no such file 'assets/x.dae'"},
    {"EmptyModelPath", job_with_object(R"({"file": ""})"), "scene.objects[0].file",
     "empty string"},
    {"ModelPathIsADirectory", job_with_object(R"({"file": "assets"})"), "scene.objects[0].file",
     "not a regular file"},
    {"DotDotEscape", job_with_object(R"({"file": "../outside/secret.dae"})"),
     "scene.objects[0].file", "lies outside the asset root"},
    {"DotDotEscapeToSystemFile",
     job_with_object(R"({"file": "../../../../../../../../../../etc/passwd"})"),
     "scene.objects[0].file", "lies outside the asset root"},
    {"DotDotEscapeToMissingFileRevealsNothing",
     job_with_object(R"({"file": "../outside/missing.dae"})"), "scene.objects[0].file",
     "lies outside the asset root"},
    {"AbsolutePathOutsideRoot", job_with_object(R"({"file": "{OUTSIDE}/secret.dae"})"),
     "scene.objects[0].file", "lies outside the asset root"},
    {"SymlinkPointingOutsideRoot", job_with_object(R"({"file": "assets/escape.dae"})"),
     "scene.objects[0].file", "lies outside the asset root"},
    {"SiblingFolderSharingTheRootsNamePrefix", job_with_object(R"({"file": "../jobs2/cow.dae"})"),
     "scene.objects[0].file", "lies outside the asset root"},
    {"SecondObjectIsNamed",
     job_with_object(R"({"file": "assets/cow.dae"}, {"file": "assets/cow.dae", "scale": [1, 2]})"),
     "scene.objects[1].scale", "expected 3 numbers"},
    {"DuplicateKeyInSecondObject",
     job_with_object(R"({"file": "assets/cow.dae"}, {"file": "assets/cow.dae", "file": "x"})"),
     "scene.objects[1].file", "duplicate key"},
    {"OverflowDeepInsideArrays",
     job_with_scene_keys(R"("lights": [{"position": [0, 1, 0]}, {"position": [0, -1e999, 0]}])"),
     "scene.lights[1].position[1]", "out of range"},
    {"OverflowAfterNestedArray",
     job_with_object(R"({"file": "assets/cow.dae", "scale": [1, 1, 1], "translate": 1e999})"),
     "scene.objects[0].translate", "out of range"},
    // output and name
    {"EmptyImagePath", job_with_keys(R"("output": {"image": ""})"), "output.image", "empty string"},
    {"PreviewSameAsImage", job_with_keys(R"("output": {"image": "out/a.exr", "preview": "out/./a.exr"})"),
     "output.preview", "same file"},
    {"NameWithSlash", job_with_keys(R"("name": "../x")"), "name", "must not contain '/'"},
    {"EmptyName", job_with_keys(R"("name": "")"), "name", "non-empty name"},
    // It names the result files: 300 bytes would render every tile, then fail at the merge.
    {"NameLongerThanAFileNameAllows", job_with_keys("\"name\": \"" + std::string(300, 'n') + "\""),
     "name", "a name of 300 bytes; at most 200"},
};

INSTANTIATE_TEST_SUITE_P(JobBadFiles, JobValidation, ::testing::ValuesIn(kBadJobs),
                         [](const ::testing::TestParamInfo<BadJob>& p) { return p.param.name; });

}  // namespace
}  // namespace farm
