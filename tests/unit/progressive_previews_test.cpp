// A frame's progressive previews on a real job store and tile files: announced in pass order,
// a pass done behind a later one announced with it (as the later one), the preview the fold of
// the passes done from the first on, the last pass left to the merge, and a fold that parts taken
// back invalidated made again from the files.
#include "server/scheduler/jobs/progressive_previews.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "renderer/image/pass_merge.h"
#include "renderer/image/png_reader.h"
#include "renderer/image/preview.h"
#include "renderer/job/render_settings.h"
#include "server/common/tile_codec.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kSide = 4;

// A pass's buffer over the whole 4x4 frame: every pixel the same grey (its pass number + 1) / 4,
// so that the fold of passes 0..p is known by hand.
RenderedTiles pass_tiles(int pass) {
  TileBuffer tile;
  tile.reset({0, 0, kSide, kSide}, AovSet{});
  const float v = static_cast<float>(pass + 1) / 4.0f;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) tile.rgba(x, y) = {v, v, v, 1.0f};
  }
  RenderedTiles out;
  encode_tile(tile, *out.response.mutable_tile());
  return out;
}

// A 4x4 job of one tile a pass, in three passes: unit k is pass k.
NewJob three_passes(const std::string& id) {
  NewJob j;
  j.id = id;
  j.name = "job " + id;
  j.spec.set_job_json("{}");
  j.scene_hash = std::string(64, 'a');
  j.engine = "path";
  j.width = j.height = kSide;
  j.passes = 3;
  j.tiles = {{0, 0, kSide, kSide}};
  return j;
}

class ProgressivePreviewsTest : public ::testing::Test {
 protected:
  ProgressivePreviewsTest() : store_(dir_ / "jobs.db"), files_(dir_ / "tiles"), events_(store_) {
    auto job = std::make_shared<Job>();
    job->render.engine = EngineKind::Path;
    job->render.width = job->render.height = kSide;
    job->render.spp = 3;
    job->render.pass_spp = 1;  // three passes of one sample
    info_.job = job;
    store_.jobs().add_job(three_passes("p"), 1);
    events_.subscribe("p", queue_);
  }

  // Claims the next unit (pass order), keeps its pixels and marks it done.
  UnitBatch render_next() {
    const std::optional<UnitBatch> b = store_.units().claim_next_batch("w", 2);
    EXPECT_TRUE(b);
    RenderedTiles tiles = pass_tiles(b->pass);
    files_.add("p", info_.frame(0), {b->first, b->pass}, tiles);
    return *b;
  }
  void done(const UnitBatch& b) { EXPECT_TRUE(store_.units().batch_done("p", b.first, b.count, {})); }

  // The passes announced since the last call.
  std::vector<int> announced() {
    std::vector<int> passes;
    v1::JobEvent event;
    while (queue_->pop(event, 0ms)) {
      if (event.has_pass_finished()) passes.push_back(event.pass_finished().pass());
    }
    return passes;
  }

  // The preview's first pixel, as stored: the fold's grey in sRGB 8-bit.
  int read_preview_pixel() {
    std::FILE* f = std::fopen(file_.c_str(), "rb");
    EXPECT_NE(f, nullptr) << file_;
    if (!f) return -1;
    const DecodedImage image = read_png(f, file_, 64);
    std::fclose(f);
    EXPECT_EQ(image.width, kSide);
    return static_cast<int>(std::lround(image.values.at(0) * 255.0f));
  }

  test::TempDir dir_;
  JobStore store_;
  TileFileAssembly files_;
  JobEvents events_;
  std::shared_ptr<JobEventQueue> queue_ = std::make_shared<JobEventQueue>();
  JobInfo info_;
  fs::path file_ = dir_ / "progress.png";
  ProgressivePreviews previews_{store_, files_, events_};
};

TEST_F(ProgressivePreviewsTest, PassesAreAnnouncedInOrderAndALatePassWithTheOneAfterIt) {
  const UnitBatch p0 = render_next(), p1 = render_next(), p2 = render_next();
  ASSERT_EQ(p0.pass, 0);
  ASSERT_EQ(p2.pass, 2);

  // Pass 1 done before pass 0: nothing to show yet.
  done(p1);
  previews_.update("p", info_, 0, file_);
  EXPECT_TRUE(announced().empty());
  EXPECT_FALSE(fs::exists(file_));

  // Pass 0 done: passes 0 and 1 are shown, announced once, as pass 1.
  done(p0);
  previews_.update("p", info_, 0, file_);
  EXPECT_EQ(announced(), std::vector<int>{1});
  ASSERT_TRUE(fs::exists(file_));
  // The mean of 0.25 and 0.5, in sRGB 8-bit.
  EXPECT_EQ(read_preview_pixel(), static_cast<int>(to_srgb8(0.375f)));
  previews_.update("p", info_, 0, file_);  // nothing new: nothing announced again
  EXPECT_TRUE(announced().empty());

  // The last pass is the merge's: update leaves it, frame_merged announces it.
  done(p2);
  previews_.update("p", info_, 0, file_);
  EXPECT_TRUE(announced().empty());
  previews_.frame_merged("p", info_, 0);
  EXPECT_EQ(announced(), std::vector<int>{2});
}

TEST_F(ProgressivePreviewsTest, AFoldWhosePartsWereTakenBackIsMadeAgainFromTheFiles) {
  const UnitBatch p0 = render_next();
  done(p0);
  const UnitBatch p1 = render_next();
  previews_.update("p", info_, 0, file_);
  EXPECT_EQ(announced(), std::vector<int>{0});
  EXPECT_EQ(read_preview_pixel(), static_cast<int>(to_srgb8(0.25f)));

  // Pass 0 taken back and rendered again (as another grey: a quarantined worker's pixels were
  // wrong); pass 1 done meanwhile. The preview folds the new pass 0 from its file, not the old.
  ASSERT_EQ(store_.units().requeue_parts("p", {p0.first}).size(), 1u);
  previews_.parts_taken_back("p");
  done(p1);
  const std::optional<UnitBatch> again = store_.units().claim_next_batch("w", 3);
  ASSERT_TRUE(again);
  ASSERT_EQ(again->pass, 0);
  RenderedTiles redone = pass_tiles(2);  // grey 0.75 this time
  files_.add("p", info_.frame(0), {again->first, 0}, redone);
  done(*again);
  previews_.update("p", info_, 0, file_);
  EXPECT_EQ(announced(), std::vector<int>{1});
  EXPECT_EQ(read_preview_pixel(), static_cast<int>(to_srgb8(0.625f)));  // (0.75 + 0.5) / 2
}

}  // namespace
}  // namespace farm
