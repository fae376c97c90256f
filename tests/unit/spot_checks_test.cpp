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
  const std::optional<UnitSpan> span = all.span(batch, 8, r);
  ASSERT_TRUE(span);
  EXPECT_EQ(span->first, 5u);
  EXPECT_EQ(span->count, 3u);
  EXPECT_EQ(span->rect, (Rect{32, 32, 100, 40}));
  EXPECT_FALSE(none.span(batch, 8, r));
  // With a small fraction only the job's own tile is chosen: a span of one tile, or none.
  const SpotCheckChooser one(1e-12, 7);
  int spans = 0;
  for (std::uint32_t first = 0; first < 8; ++first) {
    const UnitBatch single{"job", first, 1, Rect{}, 0};
    if (const auto s = one.span(single, 8, r)) {
      ++spans;
      EXPECT_EQ(s->count, 1u);
      EXPECT_EQ(s->rect.width(), first % 4 == 3 ? 4 : 32);
    }
  }
  EXPECT_EQ(spans, 1);
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
