#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "renderer/job/scene_builder.h"
#include "renderer/util/input_error.h"
#include "server/common/scene_hash.h"
#include "server/common/scene_materializer.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

class SceneMaterializer : public ::testing::Test {
 protected:
  // Puts the Cornell box's files into the store.
  void store_cornell_assets() {
    for (const auto& [path, file] : test::cornell_assets()) store_.add(test::read_file(file));
  }
  MaterializedScene materialize(const v1::JobSpec& spec) {
    return materialize_scene(spec, scene_hash(spec), store_, dir_ / "cache");
  }

  test::TempDir dir_;
  AssetStore store_{dir_ / "blobs"};
};

TEST_F(SceneMaterializer, ObjWithMtlJobIsLaidOutAndLoads) {
  store_cornell_assets();
  const v1::JobSpec spec = test::cornell_job_spec("raster", 32, 24, 1);
  const MaterializedScene m = materialize(spec);
  EXPECT_EQ(m.dir, fs::canonical(dir_ / "cache") / "scenes" / scene_hash(spec));
  EXPECT_TRUE(fs::is_regular_file(m.dir / "assets/cornell_box.obj"));
  EXPECT_TRUE(fs::is_regular_file(m.dir / "assets/cornell_box.mtl"));
  EXPECT_EQ(test::read_file(m.dir / "cornell.json"), spec.job_json());
  ASSERT_EQ(m.job.scene.objects.size(), 1u);
  EXPECT_EQ(m.job.scene.objects[0].file, m.dir / "assets/cornell_box.obj");
  EXPECT_EQ(m.job.render.width, 32);

  // The MTL was found beside the OBJ: the walls have their own colours, not the default grey.
  const Scene scene = build_scene(m.job);
  ASSERT_EQ(scene.objects.size(), 1u);
  bool red = false;
  for (const Material& mat : scene.objects[0].materials) {
    red = red || (mat.diffuse.x > 0.5f && mat.diffuse.y < 0.2f);
  }
  EXPECT_TRUE(red);

  // Again: the published folder is reused.
  EXPECT_EQ(materialize(spec).dir, m.dir);
}

// The file name is not part of the scene hash: the same job under another name finds its text
// in the published folder under that name too (the scene check in a child process reads it there).
TEST_F(SceneMaterializer, TheSameSceneUnderAnotherFileNameHasItsJobFileToo) {
  store_cornell_assets();
  v1::JobSpec spec = test::cornell_job_spec("raster", 32, 24, 1);
  const MaterializedScene first = materialize(spec);
  spec.set_file_name("renamed.json");
  const MaterializedScene second = materialize(spec);
  EXPECT_EQ(second.dir, first.dir);
  EXPECT_EQ(second.job_file, first.dir / "renamed.json");
  EXPECT_EQ(test::read_file(second.job_file), spec.job_json());
  EXPECT_EQ(test::read_file(first.job_file), spec.job_json());
}

TEST_F(SceneMaterializer, PathsThatCouldEscapeAreRejected) {
  store_cornell_assets();
  const std::vector<std::string> bad_paths{"../cornell_box.obj", "assets/../../x.obj",
                                           "/etc/passwd", "", std::string("a\0b", 3)};
  for (const std::string& bad : bad_paths) {
    v1::JobSpec spec = test::cornell_job_spec("raster", 8, 8, 1);
    spec.mutable_assets(0)->set_path(bad);
    EXPECT_THROW(validate_asset_refs(spec), InputError) << bad;
    EXPECT_THROW(materialize(spec), InputError) << bad;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x.obj"));
}

// Lengths a file system cannot hold, and more files than any scene needs, are named before
// anything is laid out; a job file name too long to keep is replaced by the default one.
TEST_F(SceneMaterializer, PathsTooLongForTheFileSystemAndTooManyFilesAreRefused) {
  store_cornell_assets();
  const auto error_of = [](const v1::JobSpec& spec) {
    try {
      validate_asset_refs(spec);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  v1::JobSpec spec = test::cornell_job_spec("raster", 8, 8, 1);
  spec.mutable_assets(0)->set_path("assets/" + std::string(256, 'n') + ".obj");
  EXPECT_NE(error_of(spec).find("a name of 260 bytes; a file name holds at most 255"), std::string::npos)
      << error_of(spec);
  std::string deep;
  for (int i = 0; i < 250; ++i) deep += "dir" + std::to_string(i % 10) + "/";  // 1250 bytes
  spec.mutable_assets(0)->set_path(deep + "x.obj");
  EXPECT_NE(error_of(spec).find("bytes long; at most 1024"), std::string::npos) << error_of(spec);

  spec = test::cornell_job_spec("raster", 8, 8, 1);
  while (spec.assets_size() <= kMaxJobAssets) *spec.add_assets() = spec.assets(0);
  EXPECT_NE(error_of(spec).find("the job lists 10001 asset files; at most 10000"), std::string::npos);

  spec = test::cornell_job_spec("raster", 8, 8, 1);
  spec.set_file_name(std::string(300, 'j') + ".json");
  const MaterializedScene m = materialize(spec);
  EXPECT_EQ(m.job_file.filename(), "job.json");
}

TEST_F(SceneMaterializer, DuplicatePathsAndBadHashesAreRejected) {
  v1::JobSpec spec = test::cornell_job_spec("raster", 8, 8, 1);
  *spec.add_assets() = spec.assets(0);
  EXPECT_THROW(validate_asset_refs(spec), InputError);
  spec = test::cornell_job_spec("raster", 8, 8, 1);
  spec.mutable_assets(0)->set_sha256("not-a-hash");
  EXPECT_THROW(validate_asset_refs(spec), InputError);
}

TEST_F(SceneMaterializer, MissingBlobIsNamed) {
  store_.add(test::read_file(test::cornell_assets()[0].second));  // the OBJ only
  const v1::JobSpec spec = test::cornell_job_spec("raster", 8, 8, 1);
  ASSERT_EQ(missing_assets(spec, store_).size(), 1u);
  try {
    materialize(spec);
    FAIL() << "expected MissingAssetsError";
  } catch (const MissingAssetsError& e) {
    ASSERT_EQ(e.missing().size(), 1u);
    EXPECT_EQ(e.missing()[0].path(), "assets/cornell_box.mtl");
    EXPECT_NE(std::string(e.what()).find("assets/cornell_box.mtl"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(dir_ / "cache/scenes" / scene_hash(spec)));
}

// A blob changed on disk after it was verified (bytes flipped, or cut short) is not laid out: it
// is removed and named, so that the client uploads it again, and then the scene materializes.
TEST_F(SceneMaterializer, ADamagedBlobIsRemovedAndNamedNotUsed) {
  const v1::JobSpec spec = test::cornell_job_spec("raster", 32, 24, 1);
  for (const bool truncate : {false, true}) {
    store_cornell_assets();
    const v1::AssetRef& obj = *std::find_if(spec.assets().begin(), spec.assets().end(),
                                            [](const v1::AssetRef& r) { return r.path().ends_with(".obj"); });
    const fs::path blob = store_.path_of(obj.sha256());
    std::string bytes = test::read_file(blob);
    if (truncate) {
      bytes.resize(bytes.size() / 2);
    } else {
      for (std::size_t i = 0; i < 16; ++i) bytes[bytes.size() / 2 + i] ^= 0x5a;
    }
    fs::remove(blob);  // not through the hard link a laid-out scene may share
    std::ofstream(blob, std::ios::binary) << bytes;
    EXPECT_TRUE(store_.has(obj.sha256()));
    EXPECT_FALSE(store_.intact(obj.sha256()));
    fs::remove_all(dir_ / "cache");
    try {
      materialize(spec);
      ADD_FAILURE() << "a damaged blob was used (truncated: " << truncate << ")";
    } catch (const CorruptAssetsError& e) {
      EXPECT_NE(std::string(e.what()).find(obj.path()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(obj.sha256()), std::string::npos) << e.what();
      ASSERT_EQ(e.missing().size(), 1u);
      EXPECT_EQ(e.missing()[0].sha256(), obj.sha256());
    }
    EXPECT_FALSE(store_.has(obj.sha256()));
    EXPECT_FALSE(fs::exists(dir_ / "cache" / "scenes" / scene_hash(spec)));
    store_cornell_assets();  // uploaded again
    EXPECT_TRUE(store_.intact(obj.sha256()));
    EXPECT_EQ(materialize(spec).job.render.width, 32);
  }
}

// A scene folder already laid out (a worker restarted on its cache) is checked before it is
// used (issue #32: a file of it damaged on disk rendered a job with 92% of its pixels wrong).
// Damaged through the blob it links to: refused and the blob removed, to be sent again. Damaged
// alone (a copy, or replaced): laid out again from the intact blob.
TEST_F(SceneMaterializer, ADamagedFileOfALaidOutSceneIsNeverLoaded) {
  const v1::JobSpec spec = test::cornell_job_spec("raster", 32, 24, 1);
  const v1::AssetRef& obj = *std::find_if(spec.assets().begin(), spec.assets().end(),
                                          [](const v1::AssetRef& r) { return r.path().ends_with(".obj"); });
  const auto flip_bytes = [](const fs::path& file) {  // in place: every hard link sees it
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(100);
    char c = 0;
    f.get(c);
    f.seekp(100);
    f.put(static_cast<char>(c ^ 0x5a));
  };
  store_cornell_assets();
  const MaterializedScene first = materialize(spec);
  const fs::path laid_out = first.dir / obj.path();
  const std::string good = test::read_file(laid_out);

  // Through the link: the blob is damaged too.
  flip_bytes(laid_out);
  try {
    materialize(spec);
    ADD_FAILURE() << "a damaged laid-out file was used";
  } catch (const CorruptAssetsError& e) {
    EXPECT_NE(std::string(e.what()).find(obj.path()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(store_.has(obj.sha256()));
  store_cornell_assets();  // sent again
  EXPECT_EQ(test::read_file(materialize(spec).dir / obj.path()), good);

  // The laid-out file alone (its link broken): laid out again, the blob kept.
  fs::remove(laid_out);
  std::string damaged = good;
  damaged[100] ^= 0x5a;
  std::ofstream(laid_out, std::ios::binary) << damaged;
  const MaterializedScene again = materialize(spec);
  EXPECT_EQ(test::read_file(again.dir / obj.path()), good);
  EXPECT_TRUE(store_.intact(obj.sha256()));
  EXPECT_EQ(again.job.render.width, 32);
}

TEST_F(SceneMaterializer, BadJobMessageNamesTheSubmittedFileNotTheCache) {
  store_cornell_assets();
  v1::JobSpec spec = test::cornell_job_spec("raster", 8, 8, 1);
  spec.set_job_json(R"({"version": 1, "scene": {"objects": [{"file": "assets/cornell_box.obj"}]},
                        "render": {"width": -5}})");
  try {
    materialize(spec);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("cornell.json: render.width", 0), 0u) << message;
    EXPECT_EQ(message.find((dir_ / "cache").string()), std::string::npos) << message;
  }
}

TEST(SceneHash, DependsOnJobAndAssetsButNotOnTheirOrder) {
  const v1::JobSpec a = test::cornell_job_spec("raster", 8, 8, 1);
  v1::JobSpec reordered = a;
  reordered.mutable_assets()->SwapElements(0, 1);
  reordered.set_file_name("other-name.json");
  EXPECT_EQ(scene_hash(a), scene_hash(reordered));
  EXPECT_NE(scene_hash(a), scene_hash(test::cornell_job_spec("raster", 8, 9, 1)));
  v1::JobSpec other_bytes = a;
  other_bytes.mutable_assets(1)->set_sha256(std::string(64, '0'));
  EXPECT_NE(scene_hash(a), scene_hash(other_bytes));
  v1::JobSpec renamed = a;
  renamed.mutable_assets(1)->set_path("assets/other.mtl");
  EXPECT_NE(scene_hash(a), scene_hash(renamed));
  EXPECT_EQ(scene_hash(a).size(), 64u);
}

}  // namespace
}  // namespace farm
