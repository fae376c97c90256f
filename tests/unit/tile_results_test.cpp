// The scheduler's tile result files: what is written reads back, and a file missing, cut short,
// grown or with bytes changed is refused with its name, never parsed into pixels.
#include "server/scheduler/jobs/tile_results.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

v1::RenderTileResponse sample_result() {
  v1::RenderTileResponse r;
  r.mutable_tile()->set_width(4);
  r.mutable_tile()->set_height(2);
  std::string pixels;
  for (int i = 0; i < 256; ++i) pixels.push_back(static_cast<char>(i));
  r.mutable_tile()->set_rgba(pixels);
  r.mutable_stats()->set_samples(42);
  return r;
}

void rewrite(const fs::path& file, const std::function<void(std::string&)>& change) {
  std::string bytes = test::read_file(file);
  change(bytes);
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(TileResultsTest, AWrittenResultReadsBackAndNoTemporaryFileStays) {
  test::TempDir dir;
  const TileResults results(dir / "tiles");
  results.write("job", 7, sample_result());
  const v1::RenderTileResponse back = results.read("job", 7);
  EXPECT_EQ(back.SerializeAsString(), sample_result().SerializeAsString());
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir / "tiles" / "job")) {
    EXPECT_EQ(e.path().filename(), "7");
    ++files;
  }
  EXPECT_EQ(files, 1);
}

TEST(TileResultsTest, AMissingTruncatedGrownOrChangedFileIsRefusedWithItsName) {
  const std::vector<std::pair<std::string, std::function<void(const fs::path&)>>> damages{
      {"deleted", [](const fs::path& f) { fs::remove(f); }},
      {"emptied", [](const fs::path& f) { fs::resize_file(f, 0); }},
      {"truncated in the header", [](const fs::path& f) { fs::resize_file(f, 20); }},
      {"truncated in the payload", [](const fs::path& f) { fs::resize_file(f, fs::file_size(f) - 10); }},
      {"grown", [](const fs::path& f) { rewrite(f, [](std::string& b) { b += "more"; }); }},
      {"16 bytes flipped in the payload",
       [](const fs::path& f) {
         rewrite(f, [](std::string& b) {
           for (std::size_t i = b.size() - 40; i < b.size() - 24; ++i) b[i] = static_cast<char>(~b[i]);
         });
       }},
      {"one bit flipped in the checksum", [](const fs::path& f) { rewrite(f, [](std::string& b) { b[20] ^= 1; }); }},
      {"length changed", [](const fs::path& f) { rewrite(f, [](std::string& b) { b[8] ^= 4; }); }},
      {"an unframed result (the old format)",
       [](const fs::path& f) { std::ofstream(f, std::ios::trunc) << sample_result().SerializeAsString(); }},
  };
  for (const auto& [what, damage] : damages) {
    test::TempDir dir;
    const TileResults results(dir / "tiles");
    results.write("job", 3, sample_result());
    const fs::path file = results.path_of("job", 3);
    damage(file);
    try {
      results.read("job", 3);
      ADD_FAILURE() << what << ": read back";
    } catch (const DamagedTileResult& e) {
      EXPECT_EQ(e.file(), file) << what;
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << what << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace farm
