// PlanSubmission: the scheduler, from the blobs it holds, asks for exactly the files the C++
// client's scanner finds on disk, in a bounded number of rounds, and refuses what SubmitJob
// refuses, with the same words.
#include "server/scheduler/jobs/submission_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "renderer/util/input_error.h"
#include "server/client/model_dependencies.h"
#include "server/common/asset_store.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// A client that answers the scheduler's plan from a folder on disk, as the Python client does:
// uploads what is missing, describes what is needed (or lists it absent), until complete.
struct PlanningClient {
  fs::path root;
  AssetStore& store;
  v1::PlanSubmissionRequest request;
  std::map<std::string, fs::path> by_sha;  // what to upload
  int rounds = 0;

  void describe(const std::string& path) {
    const fs::path file = root / path;
    if (!fs::is_regular_file(file)) {
      request.add_absent(path);
      return;
    }
    const std::string bytes = test::read_file(file);
    v1::AssetRef* ref = request.mutable_job()->add_assets();
    ref->set_path(path);
    ref->set_sha256(sha256_hex(bytes));
    ref->set_size(bytes.size());
    by_sha[ref->sha256()] = file;
  }

  // The asset paths the job sends once the plan is complete.
  std::set<std::string> plan(int max_rounds = 20) {
    for (rounds = 1; rounds <= max_rounds; ++rounds) {
      const v1::PlanSubmissionResponse response = plan_submission(request, store, SubmitLimits{});
      for (const std::string& sha : response.missing_sha256()) store.add(test::read_file(by_sha.at(sha)));
      for (const v1::NeededFile& needed : response.needed()) describe(needed.path());
      if (response.complete()) break;
    }
    std::set<std::string> paths;
    for (const v1::AssetRef& ref : request.job().assets()) paths.insert(ref.path());
    return paths;
  }
};

std::string job_of(const std::vector<std::string>& models) {
  std::string objects;
  for (const std::string& m : models) objects += (objects.empty() ? "" : ", ") + ("{\"file\": \"" + m + "\"}");
  return "{\"version\": 1, \"scene\": {\"objects\": [" + objects + "]}}";
}

// What the C++ client sends for `model` (under `root`): the model and its dependencies, as asset paths.
std::set<std::string> client_assets(const fs::path& root, const std::string& model) {
  ModelDependencyScanner scanner(root);
  const fs::path resolved = fs::weakly_canonical(root / model);
  const fs::path canonical_root = fs::weakly_canonical(root);
  std::set<std::string> out{resolved.lexically_relative(canonical_root).generic_string()};
  for (const ConfinedFile& f : scanner.dependencies(resolved)) {
    out.insert(f.named.lexically_relative(canonical_root).generic_string());
  }
  return out;
}

class SubmissionPlanTest : public ::testing::Test {
 protected:
  SubmissionPlanTest() : store_(blobs_.path()) {
    // The lab's models with what they name (OBJ + MTL, COLLADA), where the checkout has them,
    // beside models whose references every format can make: maps, buffers, images, missing ones.
    const fs::path shared = FARM_SHARED_ASSETS;
    for (const char* folder : {"obj", "dae"}) {
      if (fs::is_directory(shared / folder)) fs::copy(shared / folder, root_ / folder, fs::copy_options::recursive);
    }
    root_.write("m/box.obj", "mtllib mats/box.mtl\nmtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    root_.write("m/mats/box.mtl", "newmtl a\nKd 1 1 1\nmap_Kd -s 1 1 1 ../tex/wood.png\nbump tex/missing.png\n");
    root_.write("m/tex/wood.png", "png");
    root_.write("g/scene.gltf", R"({"asset": {"version": "2.0"},
        "buffers": [{"uri": "mesh%20data.bin", "byteLength": 3}, {"uri": "data:application/octet-stream;base64,AAAA"}],
        "images": [{"uri": "img/albedo.png"}, {"uri": "https://example.com/x.png"}, {"uri": "img/none.png"}]})");
    root_.write("g/mesh data.bin", "bin");
    root_.write("g/img/albedo.png", "png");
    root_.write("d/skinned.dae",
                "<COLLADA><library_images><image id=\"i\"><init_from>skin.png</init_from></image>"
                "<image id=\"j\"><init_from><ref>file://maps/spec%20ular.png</ref></init_from></image>"
                "</library_images><surface><init_from>i</init_from></surface></COLLADA>");
    root_.write("d/skin.png", "png");
    root_.write("d/maps/spec ular.png", "png");
  }

  PlanningClient client(const std::vector<std::string>& models) {
    PlanningClient c{root_.path(), store_, {}, {}, 0};
    c.request.mutable_job()->set_job_json(job_of(models));
    c.request.mutable_job()->set_file_name("job.json");
    for (const std::string& m : models) c.describe(m);
    return c;
  }

  TempDir root_, blobs_;
  AssetStore store_;
};

TEST_F(SubmissionPlanTest, AsksForExactlyTheFilesTheClientScannerFinds) {
  std::vector<std::string> models{"m/box.obj", "g/scene.gltf", "d/skinned.dae"};
  for (const auto& e : fs::recursive_directory_iterator(root_.path())) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".dae") models.push_back(fs::relative(e.path(), root_.path()).generic_string());
  }
  std::sort(models.begin(), models.end());
  models.erase(std::unique(models.begin(), models.end()), models.end());
  for (const std::string& model : models) {
    PlanningClient c = client({model});
    EXPECT_EQ(c.plan(), client_assets(root_.path(), model)) << model;
  }
  // The fixtures name what the formats name.
  EXPECT_EQ(client_assets(root_.path(), "m/box.obj"),
            (std::set<std::string>{"m/box.obj", "m/mats/box.mtl", "m/tex/wood.png"}));
  EXPECT_EQ(client_assets(root_.path(), "g/scene.gltf"),
            (std::set<std::string>{"g/scene.gltf", "g/mesh data.bin", "g/img/albedo.png"}));
  EXPECT_EQ(client_assets(root_.path(), "d/skinned.dae"),
            (std::set<std::string>{"d/skinned.dae", "d/skin.png", "d/maps/spec ular.png"}));

  // Every model of one job at once: the union.
  PlanningClient all = client(models);
  std::set<std::string> expected;
  for (const std::string& model : models) expected.merge(client_assets(root_.path(), model));
  EXPECT_EQ(all.plan(), expected);
}

TEST_F(SubmissionPlanTest, AnObjWithALibraryWithAMapTakesTwoRoundsALevelFreshAndOneHeld) {
  // Fresh: the model is uploaded, then read (the library asked for), the library uploaded, then
  // read (the map asked for), the map uploaded, then complete.
  PlanningClient fresh = client({"m/box.obj"});
  fresh.plan();
  EXPECT_EQ(fresh.rounds, 6);
  std::vector<std::string> absent(fresh.request.absent().begin(), fresh.request.absent().end());
  EXPECT_EQ(absent, (std::vector<std::string>{"m/gone.mtl", "m/mats/tex/missing.png"}));
  // The scheduler holding every blob: one round a level.
  PlanningClient held = client({"m/box.obj"});
  held.plan();
  EXPECT_EQ(held.rounds, 3);
}

TEST_F(SubmissionPlanTest, TheNeededFileSaysWhoNamesItAndHow) {
  PlanningClient c = client({"d/skinned.dae"});
  store_.add(test::read_file(root_ / "d/skinned.dae"));
  const v1::PlanSubmissionResponse r = plan_submission(c.request, store_, SubmitLimits{});
  ASSERT_EQ(r.needed_size(), 2);
  EXPECT_EQ(r.needed(0).path(), "d/maps/spec ular.png");
  EXPECT_EQ(r.needed(0).named_by(), "d/skinned.dae");
  EXPECT_EQ(r.needed(0).reference(), "file://maps/spec%20ular.png");
  EXPECT_EQ(r.needed(1).path(), "d/skin.png");
  EXPECT_TRUE(r.missing_sha256().empty());
  EXPECT_FALSE(r.complete());
}

std::string refusal(const v1::PlanSubmissionRequest& request, const AssetStore& store) {
  try {
    plan_submission(request, store, SubmitLimits{});
  } catch (const InputError& e) {
    return e.what();
  } catch (const ServiceError& e) {
    return e.what();
  }
  return "accepted";
}

TEST_F(SubmissionPlanTest, AnEnvironmentMapIsAskedForByTheJobAndNeverScanned) {
  // A "map" named and written like an OBJ naming a library: were it scanned as a model, the
  // library would be asked for too. (A plan reads no pixels; the worker's decode refuses it.)
  root_.write("sky/sky.obj", "mtllib trap.mtl\n");
  root_.write("sky/trap.mtl", "newmtl a\n");
  PlanningClient c = client({"m/box.obj"});
  c.request.mutable_job()->set_job_json(
      R"({"version": 1, "scene": {"objects": [{"file": "m/box.obj"}], "environment": {"map": "sky/sky.obj"}}})");
  const v1::PlanSubmissionResponse first = plan_submission(c.request, store_, SubmitLimits{});
  ASSERT_EQ(first.needed_size(), 1);
  EXPECT_EQ(first.needed(0).path(), "sky/sky.obj");
  EXPECT_EQ(first.needed(0).named_by(), "job.json");
  EXPECT_EQ(c.plan(), (std::set<std::string>{"m/box.obj", "m/mats/box.mtl", "m/tex/wood.png", "sky/sky.obj"}));

  // Listed absent by the client: refused, naming the job's key.
  PlanningClient gone = client({"m/box.obj"});
  gone.request.mutable_job()->set_job_json(
      R"({"version": 1, "scene": {"objects": [{"file": "m/box.obj"}], "environment": {"map": "sky/none.hdr"}}})");
  gone.request.add_absent("sky/none.hdr");
  const std::string why = refusal(gone.request, store_);
  EXPECT_NE(why.find("scene.environment.map: no such file 'sky/none.hdr'"), std::string::npos) << why;
}


TEST_F(SubmissionPlanTest, AReferenceOutOfTheJobsFolderIsRefusedNamingTheModelAndTheReference) {
  root_.write("x/out.obj", "mtllib ../../elsewhere.mtl\n");
  root_.write("x/abs.obj", "mtllib /etc/passwd\n");
  root_.write("x/lib.obj", "mtllib lib.mtl\n");
  root_.write("x/lib.mtl", "map_Kd ../../../secret.png\n");
  for (const char* model : {"x/out.obj", "x/abs.obj", "x/lib.obj", "x/lib.mtl"}) store_.add(test::read_file(root_ / model));
  EXPECT_EQ(refusal(client({"x/out.obj"}).request, store_),
            "x/out.obj: '../../elsewhere.mtl' lies outside the asset root (the job's folder)");
  EXPECT_EQ(refusal(client({"x/abs.obj"}).request, store_),
            "x/abs.obj: '/etc/passwd' is an absolute path (a model names its files relative to its own folder)");
  root_.write("x/latin1.obj", "mtllib caf\xe9.mtl\n");
  store_.add(test::read_file(root_ / "x/latin1.obj"));
  EXPECT_EQ(refusal(client({"x/latin1.obj"}).request, store_),
            "x/latin1.obj: 'caf\xe9.mtl' is not UTF-8, and a plan names files in UTF-8");
  PlanningClient lib = client({"x/lib.obj"});
  lib.describe("x/lib.mtl");
  EXPECT_EQ(refusal(lib.request, store_),
            "x/lib.obj: x/lib.mtl: '../../../secret.png' lies outside the asset root (the job's folder)");
}

TEST_F(SubmissionPlanTest, ASpecSubmitJobWouldRefuseIsRefusedBeforeAnythingIsRead) {
  PlanningClient c = client({"m/box.obj"});
  v1::PlanSubmissionRequest bogus = c.request;
  bogus.mutable_job()->mutable_assets(0)->set_path("../m/box.obj");
  EXPECT_EQ(refusal(bogus, store_), "asset path '../m/box.obj': must not contain '..'");
  bogus = c.request;
  bogus.mutable_job()->mutable_assets(0)->set_path("/m/box.obj");
  EXPECT_EQ(refusal(bogus, store_), "asset path '/m/box.obj': must be relative to the job's folder");
  bogus = c.request;
  bogus.add_absent("../../etc/passwd");
  EXPECT_EQ(refusal(bogus, store_), "asset path '../../etc/passwd': must not contain '..'");
  bogus = c.request;
  bogus.add_absent("m/box.obj");
  EXPECT_EQ(refusal(bogus, store_), "PlanSubmission: 'm/box.obj' is both an asset and absent");
  bogus = c.request;
  bogus.mutable_job()->mutable_assets(0)->set_size(std::uint64_t{3} << 30);
  EXPECT_NE(refusal(bogus, store_).find("(--max-asset-bytes)"), std::string::npos);
  // A job's own errors come back as SubmitJob gives them: the file and the JSON path.
  bogus = c.request;
  bogus.mutable_job()->set_job_json(R"({"version": 1, "scene": {"objects": [{"file": "../up.obj"}]}})");
  EXPECT_EQ(refusal(bogus, store_),
            "job.json: scene.objects[0].file: '../up.obj' lies outside the asset root (the job's folder)");
  bogus.mutable_job()->set_job_json(R"({"version": 1, "scene": {"objects": [{"file": 3}]}})");
  EXPECT_EQ(refusal(bogus, store_), "job.json: scene.objects[0].file: expected a string, got 3");
  // A model the client found nowhere.
  bogus = client({"m/nothing.obj"}).request;
  EXPECT_EQ(refusal(bogus, store_), "job.json: scene.objects[0].file: no such file 'm/nothing.obj'");
}

}  // namespace
}  // namespace farm
