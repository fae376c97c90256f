#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "renderer/util/input_error.h"
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

// An upload cut short by a crash leaves its temporary file (issue #32): a restart removes those
// whose writer is gone, and those nobody wrote to for the stale time (another host's), and keeps
// an upload in progress.
TEST(AssetStore, AStartSweepsUploadsCutShortAndKeepsLiveOnes) {
  test::TempDir dir;
  const AssetStore store(dir / "blobs");
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  ASSERT_GT(dead, 0);
  waitpid(dead, nullptr, 0);  // its PID names no process now
  const auto put = [&](const std::string& name) {
    const fs::path file = dir / "blobs" / name;
    std::ofstream(file) << "part of an upload";
    return file;
  };
  const fs::path crashed = put(".tmp-0123456789abcdef-" + std::to_string(dead) + "-0");
  const fs::path live = put(".tmp-0123456789abcdef-" + std::to_string(::getpid()) + "-1");
  const fs::path abandoned = put(".tmp-0123456789abcdef-" + std::to_string(::getppid()) + "-2");
  fs::last_write_time(abandoned, fs::file_time_type::clock::now() - std::chrono::hours(2));
  const std::string blob = store.add("a published blob");
  EXPECT_EQ(store.sweep_abandoned_uploads(), 2u);
  EXPECT_FALSE(fs::exists(crashed));
  EXPECT_FALSE(fs::exists(abandoned));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(store.intact(blob));
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
