// Keyframe interpolation (renderer/job/keyframes.h) against values worked out by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "renderer/job/frame_range.h"
#include "renderer/job/keyframes.h"

namespace farm {
namespace {

KeyframeTrack track(Interpolation i, std::vector<Keyframe> keys) {
  KeyframeTrack t;
  t.path = "scene.ambient";
  t.interpolation = i;
  t.keys = std::move(keys);
  return t;
}

double at(const KeyframeTrack& t, double frame) { return t.at(frame).at(0); }

TEST(Keyframes, LinearIsStraightBetweenKeysAndHoldsOutside) {
  const KeyframeTrack t = track(Interpolation::Linear, {{1, {0}}, {49, {360}}});
  EXPECT_DOUBLE_EQ(at(t, 13), 90.0);   // 360 * 12 / 48
  EXPECT_DOUBLE_EQ(at(t, 25), 180.0);
  EXPECT_DOUBLE_EQ(at(t, 1), 0.0);
  EXPECT_DOUBLE_EQ(at(t, 49), 360.0);
  EXPECT_DOUBLE_EQ(at(t, -5), 0.0);    // before the first key: holds
  EXPECT_DOUBLE_EQ(at(t, 100), 360.0); // after the last: holds
}

TEST(Keyframes, RotationDegreesInterpolateAsNumbersThroughWholeTurns) {
  // 0 -> 720 degrees is two whole turns: halfway is 360 (a full turn), not the 0 of a matrix blend.
  const KeyframeTrack t = track(Interpolation::Linear, {{0, {0}}, {10, {720}}});
  EXPECT_DOUBLE_EQ(at(t, 5), 360.0);
  EXPECT_DOUBLE_EQ(at(t, 2.5), 180.0);
}

TEST(Keyframes, StepHoldsEachKeyUntilTheNext) {
  const KeyframeTrack t = track(Interpolation::Step, {{1, {2}}, {5, {7}}, {9, {-1}}});
  EXPECT_DOUBLE_EQ(at(t, 1), 2.0);
  EXPECT_DOUBLE_EQ(at(t, 4.99), 2.0);
  EXPECT_DOUBLE_EQ(at(t, 5), 7.0);
  EXPECT_DOUBLE_EQ(at(t, 8), 7.0);
  EXPECT_DOUBLE_EQ(at(t, 9), -1.0);
  EXPECT_DOUBLE_EQ(at(t, 0), 2.0);
  EXPECT_DOUBLE_EQ(at(t, 20), -1.0);
}

TEST(Keyframes, SmoothIsCatmullRomThroughTheKeys) {
  // Keys (0,0) (1,1) (2,0) (3,1). Slopes: m0 = (1-0)/1 = 1 (one-sided), m1 = (0-0)/2 = 0,
  // m2 = (1-1)/2 = 0, m3 = 1. On [1, 2] at s = 0.5 the Hermite basis gives
  // h00 = h01 = 0.5, h10 = 0.125, h11 = -0.125: 0.5*1 + 0.125*0 + 0.5*0 - 0.125*0 = 0.5.
  // On [0, 1] at s = 0.5: 0.5*0 + 0.125*1*1 + 0.5*1 - 0.125*1*0 = 0.625.
  const KeyframeTrack t = track(Interpolation::Smooth, {{0, {0}}, {1, {1}}, {2, {0}}, {3, {1}}});
  EXPECT_NEAR(at(t, 1.5), 0.5, 1e-12);
  EXPECT_NEAR(at(t, 0.5), 0.625, 1e-12);
  EXPECT_DOUBLE_EQ(at(t, 1), 1.0);  // through every key
  EXPECT_DOUBLE_EQ(at(t, 2), 0.0);
  EXPECT_DOUBLE_EQ(at(t, -1), 0.0);  // holds
  EXPECT_DOUBLE_EQ(at(t, 4), 1.0);
}

TEST(Keyframes, SmoothWithUnevenKeysUsesSlopesPerFrame) {
  // Keys (0,0) (2,4) (3,4): m1 = (4-0)/(3-0) = 4/3 per frame. On [0, 2] at s = 0.5 (frame 1):
  // m0 = (4-0)/2 = 2, h = 2: 0.5*0 + 0.125*2*2 + 0.5*4 - 0.125*2*(4/3) = 0.5 + 2 - 1/3.
  const KeyframeTrack t = track(Interpolation::Smooth, {{0, {0}}, {2, {4}}, {3, {4}}});
  EXPECT_NEAR(at(t, 1), 0.5 + 2.0 - 1.0 / 3.0, 1e-12);
}

TEST(Keyframes, VectorsInterpolateEachComponent) {
  const KeyframeTrack t = track(Interpolation::Linear, {{0, {0, 10, -4}}, {4, {4, 2, 4}}});
  EXPECT_EQ(t.at(1), (std::vector<double>{1, 8, -2}));
}

TEST(Keyframes, OneKeyIsConstant) {
  for (Interpolation i : {Interpolation::Step, Interpolation::Linear, Interpolation::Smooth}) {
    const KeyframeTrack t = track(i, {{3, {5}}});
    EXPECT_DOUBLE_EQ(at(t, 0), 5.0);
    EXPECT_DOUBLE_EQ(at(t, 3), 5.0);
    EXPECT_DOUBLE_EQ(at(t, 9), 5.0);
  }
}

TEST(FrameRange, FramesFollowTheStepAndThePick) {
  FrameRange r;
  r.start = 1;
  r.end = 10;
  r.step = 3;
  EXPECT_EQ(r.frames(), (std::vector<int>{1, 4, 7, 10}));
  r.only = std::pair{3, 8};
  EXPECT_EQ(r.frames(), (std::vector<int>{4, 7}));
  r.fps = 2;
  EXPECT_DOUBLE_EQ(r.seconds_at(4), 1.5);
}

TEST(FrameRange, ContainsIsMembershipOfFrames) {
  for (const auto& only : {std::optional<std::pair<int, int>>{}, std::optional{std::pair{3, 8}}}) {
    FrameRange r;
    r.start = 1;
    r.end = 10;
    r.step = 3;
    r.only = only;
    const std::vector<int> frames = r.frames();
    for (int f = -2; f <= 14; ++f) {
      EXPECT_EQ(r.contains(f), std::find(frames.begin(), frames.end(), f) != frames.end()) << f;
    }
  }
}

TEST(FrameRange, FrameNamesFillTheLastRunOfHashes) {
  EXPECT_EQ(frame_file_name("out/turntable.####.exr", 7), "out/turntable.0007.exr");
  EXPECT_EQ(frame_file_name("out/t.#.exr", 123), "out/t.123.exr");  // more digits when needed
  EXPECT_EQ(frame_file_name("a#b/x_##.png", 5), "a#b/x_05.png");     // the last run only
  EXPECT_EQ(frame_file_name("plain.exr", 5), "plain.exr");
  EXPECT_TRUE(has_frame_pattern("out/x.####.exr"));
  EXPECT_FALSE(has_frame_pattern("out/x.exr"));
}

TEST(FrameRange, PicksParseRangesAndSingleFrames) {
  EXPECT_EQ(parse_frame_pick("10-20"), (std::pair{10, 20}));
  EXPECT_EQ(parse_frame_pick("5"), (std::pair{5, 5}));
  EXPECT_FALSE(parse_frame_pick("20-10"));
  EXPECT_FALSE(parse_frame_pick("x"));
  EXPECT_FALSE(parse_frame_pick("1-"));
  EXPECT_FALSE(parse_frame_pick("-3"));
  EXPECT_FALSE(parse_frame_pick(""));
}

}  // namespace
}  // namespace farm
