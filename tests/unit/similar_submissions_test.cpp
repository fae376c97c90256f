// The prefilters of similar_submissions (16 x 16 thumbnail distance, then the pixels' mean
// difference) never let go a pair that LDR-FLIP would call nearly identical: over shifts of
// brightness and colour, ramps, repainted blocks and noise of three kinds, on bright and dark
// pictures, every pair a prefilter rejects has a FLIP mean above the threshold, with margin.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <random>
#include <utility>
#include <vector>

#include "renderer/compare/flip.h"
#include "renderer/compare/image.h"
#include "server/grade/similar_submissions.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

// A smooth 128x96 picture with some structure: gradients and a disc.
Image scene() {
  Image image = make_image(128, 96, {"R", "G", "B"});
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const bool disc = (x - 70) * (x - 70) + (y - 45) * (y - 45) < 400;
      image.at(x, y, 0) = disc ? 0.8f : 0.2f + 0.5f * static_cast<float>(x) / 127.0f;
      image.at(x, y, 1) = disc ? 0.3f : 0.3f + 0.4f * static_cast<float>(y) / 95.0f;
      image.at(x, y, 2) = disc ? 0.2f : 0.6f;
    }
  return image;
}

// `image` with `delta` added to channel `c` (all channels when c < 0), clamped to [0, 1].
Image shifted(Image image, float delta, int c) {
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int k = 0; k < 3; ++k)
        if (c < 0 || k == c) image.at(x, y, k) = std::clamp(image.at(x, y, k) + delta, 0.0f, 1.0f);
  return image;
}

// `image` with the block [x0, x1) x [y0, y1) painted `r g b`.
Image painted(Image image, int x0, int y0, int x1, int y1, float r, float g, float b) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      image.at(x, y, 0) = r;
      image.at(x, y, 1) = g;
      image.at(x, y, 2) = b;
    }
  return image;
}

// `image` plus a ramp of `amount` times x / width on every channel: a slow change of brightness.
Image ramped(Image image, float amount) {
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int k = 0; k < 3; ++k)
        image.at(x, y, k) = std::clamp(image.at(x, y, k) + amount * static_cast<float>(x) / static_cast<float>(image.width), 0.0f, 1.0f);
  return image;
}

// `image` plus zero-mean noise of amplitude `amount`, stored at 8 bits as a PNG would: a checker
// at the highest frequency (kind 0, what FLIP's filters damp most), Gaussian noise of sigma
// `amount` (kind 1, like a path tracer's), or a checker of 4 x 4 blocks (kind 2).
Image noisy(Image image, float amount, int kind) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss(0.0f, amount);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      for (int k = 0; k < 3; ++k) {
        const float n = kind == 0 ? ((x + y) % 2 == 0 ? amount : -amount)
                        : kind == 1 ? gauss(rng)
                                    : ((x / 4 + y / 4) % 2 == 0 ? amount : -amount);
        image.at(x, y, k) = std::round(std::clamp(image.at(x, y, k) + n, 0.0f, 1.0f) * 255.0f) / 255.0f;
      }
  return image;
}

// Every difference either prefilter rejects has a FLIP mean above the threshold, with margin:
// FLIP runs at least 2 x the thumbnail distance and 0.5 x the pixel distance (the least, ~0.58,
// for the checkerboard at the highest frequency).
TEST(SimilarSubmissionsPrefilterTest, WhatThePrefiltersRejectFlipWouldNotCallAlike) {
  const SimilarityOptions defaults;
  const Image bright = scene();
  Image dark = scene();
  for (float& v : dark.values) v *= 0.15f;
  std::vector<std::pair<Image, Image>> cases;
  for (const Image* base : std::vector<const Image*>{&bright, &dark}) {
    for (int c = -1; c < 3; ++c)
      for (float delta : {-0.2f, -0.03f, 0.02f, 0.03f, 0.05f, 0.2f}) cases.emplace_back(*base, shifted(*base, delta, c));
    for (int kind = 0; kind < 3; ++kind)
      for (float amount : {0.005f, 0.01f, 0.02f, 0.05f, 0.1f, 0.3f}) cases.emplace_back(*base, noisy(*base, amount, kind));
  }
  for (float amount : {0.03f, 0.1f, 0.5f}) cases.emplace_back(bright, ramped(bright, amount));
  cases.emplace_back(bright, painted(bright, 10, 10, 26, 26, 0.9f, 0.9f, 0.1f));  // a block of another colour
  cases.emplace_back(bright, painted(bright, 60, 35, 80, 55, 0.2f, 0.6f, 0.6f));  // the disc recoloured
  cases.emplace_back(bright, painted(bright, 0, 0, 128, 48, 0.5f, 0.5f, 0.5f));   // half the picture gone
  double thumbnail_ratio = 1e9, pixel_ratio = 1e9;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const auto& [a, b] = cases[i];
    const double thumbnail = thumbnail_distance(a, b), pixels = pixel_distance(a, b);
    const double flip = flip_ldr(a, b, FlipOptions{}).mean;
    EXPECT_LE(thumbnail, pixels + 1e-6) << "case " << i;  // a lower bound (up to float rounding)
    if (thumbnail > 0.001) thumbnail_ratio = std::min(thumbnail_ratio, flip / thumbnail);
    if (pixels > 0.0) pixel_ratio = std::min(pixel_ratio, flip / pixels);
    if (thumbnail > defaults.thumbnail_tolerance || pixels > defaults.pixel_tolerance) {
      EXPECT_GE(flip, defaults.flip_threshold) << "case " << i << ": thumbnail " << thumbnail << ", pixels " << pixels;
    }
  }
  EXPECT_GT(thumbnail_ratio, 2.0);
  EXPECT_GT(pixel_ratio, 0.5);
}

// What the thumbnail cannot see (one pixel, fine noise) passes it: the pixels and FLIP decide.
TEST(SimilarSubmissionsPrefilterTest, WhatTheThumbnailCannotSeeGoesOnToThePixelsAndFlip) {
  const SimilarityOptions defaults;
  const Image a = scene();
  Image one_pixel = a;
  one_pixel.at(40, 40, 0) = 1.0f;
  one_pixel.at(40, 40, 1) = 0.0f;
  EXPECT_LT(thumbnail_distance(a, one_pixel), defaults.thumbnail_tolerance);
  EXPECT_LT(pixel_distance(a, one_pixel), defaults.pixel_tolerance);
  EXPECT_LT(flip_ldr(a, one_pixel, FlipOptions{}).mean, defaults.flip_threshold);
  const Image fine = noisy(a, 0.1f, 1);
  EXPECT_LT(thumbnail_distance(a, fine), defaults.thumbnail_tolerance);  // averaged out
  EXPECT_GT(pixel_distance(a, fine), defaults.pixel_tolerance);          // the pixels see it
  const Image faint = noisy(a, 0.005f, 1);
  EXPECT_LT(pixel_distance(a, faint), defaults.pixel_tolerance);
  EXPECT_GT(flip_ldr(a, faint, FlipOptions{}).mean, defaults.flip_threshold);  // FLIP tells them apart
  EXPECT_EQ(thumbnail_distance(a, a), 0.0);
  EXPECT_EQ(pixel_distance(a, a), 0.0);
}

// Images smaller than the thumbnail: every pixel is its own cell.
TEST(SimilarSubmissionsPrefilterTest, TinyImagesCompareEveryPixel) {
  Image a = make_image(4, 2, {"R", "G", "B"});
  Image b = a;
  b.at(3, 1, 2) = 0.6f;
  EXPECT_NEAR(thumbnail_distance(a, b), 0.6 / 24.0, 1e-6);
}

// A class of 40 students who all rendered the same scene with their own noise (sigma 0.04, a
// path tracer's at a moderate sample count), plus two who handed in one image and a third who
// changed one pixel of it: 903 pairs, all alike at 16 x 16, but the pixels tell the noisy ones
// apart, so FLIP runs only on the two pairs with the near copy.
TEST(SimilarSubmissionsBoundTest, NoisyRendersOfOneSceneCostNoFlipRuns) {
  test::TempDir dir;
  Rubric rubric;
  GradeTask task;
  task.name = "scene";
  task.points = 10;
  task.file = "scene.png";
  rubric.tasks = {task};
  ClassGrades grades;
  grades.rubric = &rubric;
  const Image clean = scene();
  const auto add = [&](const std::string& student, const Image& image) {
    StudentGrade s;
    s.student = student;
    TaskGrade t;
    t.task = "scene";
    t.max_points = 10;
    t.student_png = dir / (student + ".png");
    write_png_image(image, t.student_png);
    s.tasks = {t};
    grades.students.push_back(s);
  };
  for (int i = 0; i < 40; ++i) {
    Image image = clean;
    std::mt19937 rng(static_cast<unsigned>(100 + i));
    std::normal_distribution<float> gauss(0.0f, 0.04f);
    for (float& v : image.values) v = std::clamp(v + gauss(rng), 0.0f, 1.0f);
    add(fmt::format("noisy{:02}", i), image);
  }
  const Image copied = noisy(clean, 0.04f, 1);
  Image near = copied;
  near.at(5, 5, 2) = 1.0f - near.at(5, 5, 2);
  add("copy_a", copied);
  add("copy_b", copied);
  add("copy_c", near);
  std::sort(grades.students.begin(), grades.students.end(),
            [](const StudentGrade& a, const StudentGrade& b) { return a.student < b.student; });

  SimilarityCounts counts;
  const std::vector<SimilarPair> pairs = find_similar_submissions(grades, {}, &counts);
  EXPECT_EQ(counts.images, 43u);
  EXPECT_EQ(counts.pairs, 43u * 42u / 2u);
  EXPECT_EQ(counts.identical, 1u);
  EXPECT_GT(counts.thumbnail, 800u);  // the thumbnail cannot tell noise apart
  EXPECT_EQ(counts.flip, 2u);         // the pixels can
  ASSERT_EQ(pairs.size(), 3u);
  EXPECT_EQ(pairs[0].student_a, "copy_a");
  EXPECT_EQ(pairs[0].student_b, "copy_b");
  EXPECT_TRUE(pairs[0].identical);
  EXPECT_EQ(pairs[1].student_b, "copy_c");
  EXPECT_EQ(pairs[2].student_b, "copy_c");
  EXPECT_FALSE(pairs[1].identical);
  EXPECT_GT(pairs[1].flip_mean, 0.0);
  EXPECT_LT(pairs[1].flip_mean, 0.01);
}

}  // namespace
}  // namespace farm
