// Spot checks (server/scheduler/dispatch/spot_checks.h): which tiles are chosen, the span of a batch that
// is rendered again, and what opinions decide.
#include <gtest/gtest.h>

#include <string>

#include "server/scheduler/dispatch/spot_checks.h"

namespace farm {
namespace {

TEST(SpotCheckChooser, NoneAtZeroEveryTileAtOneAndAtLeastOneTileOfEveryJob) {
  const SpotCheckChooser none(0.0, 42), all(1.0, 42), few(1e-9, 42);
  EXPECT_FALSE(none.enabled());
  for (const std::string job : {"a", "b", "0123456789abcdef"}) {
    int chosen_all = 0, chosen_few = 0;
    for (std::uint32_t i = 0; i < 100; ++i) {
      EXPECT_FALSE(none.chosen(job, i, 100));
      chosen_all += all.chosen(job, i, 100) ? 1 : 0;
      chosen_few += few.chosen(job, i, 100) ? 1 : 0;
    }
    EXPECT_EQ(chosen_all, 100);
    EXPECT_EQ(chosen_few, 1) << job;  // the one every job gets
  }
}

TEST(SpotCheckChooser, ChoosesAboutTheFractionDeterministicallyAndTheKeyChangesWhich) {
  const SpotCheckChooser a(0.1, 1), again(0.1, 1), other_key(0.1, 2);
  int chosen = 0, same = 0, differ = 0;
  for (std::uint32_t i = 0; i < 20000; ++i) {
    const bool c = a.chosen("job", i, 20000);
    chosen += c ? 1 : 0;
    same += c == again.chosen("job", i, 20000) ? 1 : 0;
    differ += c != other_key.chosen("job", i, 20000) ? 1 : 0;
  }
  // Fixed keys: these counts are the same on every run.
  EXPECT_GT(chosen, 1800);
  EXPECT_LT(chosen, 2200);
  EXPECT_EQ(same, 20000);
  EXPECT_GT(differ, 2000);
}

TEST(SpotCheckChooser, ASpanRunsFromTheFirstChosenTileOfABatchToItsLast) {
  RenderSettings r;
  r.width = 100;  // 4 columns of 32 px tiles, the last 4 px wide; 2 rows
  r.height = 40;
  r.tile_size = 32;
  const SpotCheckChooser all(1.0, 7), none(0.0, 7);
  const UnitBatch batch{"job", 5, 3, Rect{32, 32, 100, 40}, 0};  // tiles 5, 6, 7 of row 1
  const std::optional<UnitSpan> span = all.span(batch, 8, UnitGrid(r, 0));
  ASSERT_TRUE(span);
  EXPECT_EQ(span->first, 5u);
  EXPECT_EQ(span->count, 3u);
  EXPECT_EQ(span->rect, (Rect{32, 32, 100, 40}));
  EXPECT_FALSE(none.span(batch, 8, UnitGrid(r, 0)));
  // With a small fraction only the job's own tile is chosen: a span of one tile, or none.
  const SpotCheckChooser one(1e-12, 7);
  int spans = 0;
  for (std::uint32_t first = 0; first < 8; ++first) {
    const UnitBatch single{"job", first, 1, Rect{}, 0};
    if (const auto s = one.span(single, 8, UnitGrid(r, 0))) {
      ++spans;
      EXPECT_EQ(s->count, 1u);
      EXPECT_EQ(s->rect.width(), first % 4 == 3 ? 4 : 32);
    }
  }
  EXPECT_EQ(spans, 1);
}

TEST(SpotCheckChooser, ASpanOverRowsOfABatchOfWholeRowsTakesThoseRowsWhole) {
  RenderSettings r;
  r.width = 100;  // 4 columns of 32 px tiles, the last 4 px wide; 3 rows, the last 8 px high
  r.height = 72;
  r.tile_size = 32;
  const UnitGrid grid(r, 0);
  const SpotCheckChooser all(1.0, 7);
  const UnitBatch rows{"job", 0, 12, Rect{0, 0, 100, 72}, 0};  // every row
  const std::optional<UnitSpan> span = all.span(rows, 12, grid);
  ASSERT_TRUE(span);
  EXPECT_EQ(span->first, 0u);
  EXPECT_EQ(span->count, 12u);
  EXPECT_EQ(span->rect, (Rect{0, 0, 100, 72}));
  // With a few chosen (keys 1 to 200), each span covers its units from the first to the last, its
  // rectangle is exactly those units, and some spans cross rows.
  int crossing = 0;
  for (std::uint64_t key = 1; key <= 200; ++key) {
    const std::optional<UnitSpan> s = SpotCheckChooser(0.2, key).span(rows, 12, grid);
    if (!s) continue;
    std::int64_t area = 0;
    Rect covered = grid.rect_of(s->first);
    for (std::uint32_t i = s->first; i < s->first + s->count; ++i) {
      const Rect u = grid.rect_of(i);
      covered = {std::min(covered.x0, u.x0), std::min(covered.y0, u.y0), std::max(covered.x1, u.x1),
                 std::max(covered.y1, u.y1)};
      area += static_cast<std::int64_t>(u.width()) * u.height();
    }
    EXPECT_EQ(s->rect, covered) << "key " << key;
    EXPECT_EQ(static_cast<std::int64_t>(s->rect.width()) * s->rect.height(), area) << "key " << key;
    if (covered.y1 - covered.y0 > 32) ++crossing;
  }
  EXPECT_GT(crossing, 0);
}

TEST(UnitGrid, UnitsAreWholeTilesAtLeastTheAskedEdgeAndNeverLargerThanTheImage) {
  RenderSettings r;
  r.width = 640;
  r.height = 480;
  r.tile_size = 32;
  EXPECT_EQ(UnitGrid(r, 0).edge(), 32);
  EXPECT_EQ(UnitGrid(r, 0).count(), 300u);
  EXPECT_EQ(UnitGrid(r, 256).edge(), 256);
  EXPECT_EQ(UnitGrid(r, 256).count(), 6u);  // 3 x 2
  EXPECT_EQ(UnitGrid(r, 100).edge(), 128);  // 4 tiles: the fewest that reach 100
  r.tile_size = 48;
  EXPECT_EQ(UnitGrid(r, 256).edge(), 288);  // 6 tiles of 48
  EXPECT_EQ(UnitGrid(r, 100000).edge(), 640);
  EXPECT_EQ(UnitGrid(r, 100000).count(), 1u);
  // Every unit is whole tiles, and the units cover the image once.
  r.tile_size = 32;
  const UnitGrid grid(r, 200);
  std::int64_t area = 0;
  for (const Rect& u : grid.rects()) {
    EXPECT_EQ(u.x0 % r.tile_size, 0);
    EXPECT_EQ(u.y0 % r.tile_size, 0);
    area += static_cast<std::int64_t>(u.width()) * u.height();
  }
  EXPECT_EQ(area, 640 * 480);
  EXPECT_EQ(grid.rect_of(grid.count() + 1), grid.rects()[1]);  // the next frame's units
}

Opinion opinion(const std::string& worker, float value) {
  v1::TileData t;
  t.mutable_rect()->set_x1(1);
  t.mutable_rect()->set_y1(1);
  t.set_width(1);
  t.set_height(1);
  const float rgba[4] = {value, value, value, 1.0f};
  t.set_rgba(std::string(reinterpret_cast<const char*>(rgba), sizeof rgba));
  return {worker + "-id", worker, t};
}

TEST(SpotCheckJudge, AnAgreeingSecondOpinionConfirmsTheFirst) {
  std::vector<Opinion> opinions{opinion("a", 0.5f)};
  const Judgement j = judge(opinions, opinion("b", 0.5f));
  EXPECT_EQ(j.outcome, Judgement::Outcome::Agreed);
  EXPECT_EQ(j.agreed_with, 0u);
  EXPECT_TRUE(j.wrong.empty());
  EXPECT_EQ(opinions.size(), 1u);
}

TEST(SpotCheckJudge, ThirdOpinionNamesTheWorkerThatDisagrees) {
  // The batch's own worker lied: the second and third agree.
  std::vector<Opinion> opinions{opinion("liar", 0.5f)};
  EXPECT_EQ(judge(opinions, opinion("b", 0.25f)).outcome, Judgement::Outcome::NeedAnother);
  Judgement j = judge(opinions, opinion("c", 0.25f));
  EXPECT_EQ(j.outcome, Judgement::Outcome::Agreed);
  EXPECT_EQ(j.agreed_with, 1u);
  EXPECT_EQ(j.wrong, std::vector<std::size_t>{0});

  // The checking worker lied: the third agrees with the batch's own.
  opinions = {opinion("a", 0.5f)};
  EXPECT_EQ(judge(opinions, opinion("liar", 0.75f)).outcome, Judgement::Outcome::NeedAnother);
  j = judge(opinions, opinion("c", 0.5f));
  EXPECT_EQ(j.outcome, Judgement::Outcome::Agreed);
  EXPECT_EQ(j.agreed_with, 0u);
  EXPECT_EQ(j.wrong, std::vector<std::size_t>{1});
  EXPECT_EQ(opinions[j.wrong[0]].worker, "liar");
}

TEST(SpotCheckJudge, ThreeDifferentOpinionsSettleNothing) {
  std::vector<Opinion> opinions{opinion("a", 0.5f)};
  EXPECT_EQ(judge(opinions, opinion("b", 0.25f)).outcome, Judgement::Outcome::NeedAnother);
  EXPECT_EQ(judge(opinions, opinion("c", 0.125f)).outcome, Judgement::Outcome::NoAgreement);
  EXPECT_EQ(opinions.size(), 3u);
}

}  // namespace
}  // namespace farm
