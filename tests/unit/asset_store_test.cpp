#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "renderer/scene/input_error.h"
#include "server/common/asset_store.h"
#include "server/common/sha256.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

std::size_t files_in(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(AssetStore, AddStoresTheBytesUnderTheirHash) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  const std::string sha = store.add("hello");
  EXPECT_EQ(sha, sha256_hex("hello"));
  EXPECT_TRUE(store.has(sha));
  EXPECT_EQ(store.path_of(sha), dir / "blobs" / sha);
  EXPECT_EQ(test::read_file(store.path_of(sha)), "hello");
  EXPECT_FALSE(store.has(sha256_hex("other")));
}

TEST(AssetStore, HashMismatchIsRejectedAndLeavesNothing) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  const std::string claimed = sha256_hex("the real bytes");
  EXPECT_THROW(store.put(claimed, "other bytes"), InputError);
  EXPECT_FALSE(store.has(claimed));
  EXPECT_EQ(files_in(store.dir()), 0u);  // no temporary file left behind either
}

TEST(AssetStore, SizeMismatchIsRejected) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  const std::string sha = sha256_hex("abc");
  {
    AssetStore::Writer w = store.begin(sha, 2);
    EXPECT_THROW(w.append("abc"), InputError);
  }
  {
    AssetStore::Writer w = store.begin(sha, 4);
    w.append("abc");
    EXPECT_THROW(w.commit(), InputError);
  }
  EXPECT_FALSE(store.has(sha));
  EXPECT_EQ(files_in(store.dir()), 0u);
}

TEST(AssetStore, BlobAppearsOnlyWhenCommitted) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  const std::string sha = sha256_hex("part one, part two");
  {
    AssetStore::Writer w = store.begin(sha);
    w.append("part one, ");
    EXPECT_FALSE(store.has(sha));  // half written: not visible under its name
  }  // abandoned
  EXPECT_FALSE(store.has(sha));
  EXPECT_EQ(files_in(store.dir()), 0u);

  AssetStore::Writer w = store.begin(sha);
  w.append("part one, ");
  w.append("part two");
  EXPECT_FALSE(store.has(sha));
  w.commit();
  EXPECT_TRUE(store.has(sha));
  EXPECT_EQ(files_in(store.dir()), 1u);
}

TEST(AssetStore, NamesThatAreNotHashesAreRefused) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  EXPECT_THROW(store.path_of("../../etc/passwd"), InputError);
  EXPECT_THROW(store.put("ABC", "x"), InputError);
  EXPECT_FALSE(store.has("../blobs"));
}

}  // namespace
}  // namespace farm
