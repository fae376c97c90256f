#include <gtest/gtest.h>

#include <bit>
#include <limits>

#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <glm/geometric.hpp>
#include <ImfInputFile.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <set>
#include <stdexcept>
#include <string>

#include "renderer/image/exr_io.h"
#include "renderer/util/atomic_file.h"
#include "renderer/image/preview.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

class ImageIoTest : public ::testing::Test {
 protected:
  test::TempDir dir_;
};

TileBuffer sample_film() {
  AovSet aovs;
  aovs.depth = aovs.normal = aovs.albedo = aovs.bvh_cost = aovs.variance = true;
  TileBuffer film(Rect{0, 0, 7, 5}, aovs);
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 7; ++x) {
      film.rgba(x, y) = {0.1f * x, 0.05f * y, 1.5f, x == 0 ? 0.0f : 1.0f};
      film.depth(x, y) = x == 0 ? TileBuffer::kNoDepth : 1.2345678f + static_cast<float>(x * y);
      film.normal(x, y) = glm::normalize(glm::vec3(x - 3, 1, y));
      film.albedo(x, y) = {0.8f, 0.6f, 0.4f};
      film.bvh_cost(x, y) = static_cast<float>(100 + x + 7 * y);
      // Below half's smallest normal (6e-5) and with more digits than half keeps.
      film.variance(x, y) = {1.2345678e-7f * static_cast<float>(x + 1), 3.0e-12f * static_cast<float>(y + 1),
                             0.123456789f + static_cast<float>(x * y)};
    }
  }
  return film;
}

TEST_F(ImageIoTest, ExrHalfRoundTripKeepsValuesAndStandardChannelNames) {
  const TileBuffer film = sample_film();
  const fs::path file = dir_ / "sub" / "film.exr";
  write_exr(film, file);  // creates the missing folder

  Imf::InputFile in(file.c_str());
  std::set<std::string> names;
  for (auto it = in.header().channels().begin(); it != in.header().channels().end(); ++it) {
    names.insert(it.name());
    const bool is_float = it.channel().type == Imf::FLOAT;
    const std::string name = it.name();
    EXPECT_EQ(is_float, name == "Z" || name == "bvh_cost" || name.starts_with("variance.")) << name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z", "albedo.R",
                                          "albedo.G", "albedo.B", "bvh_cost", "variance.R",
                                          "variance.G", "variance.B"}));

  const TileBuffer back = read_exr(file);
  ASSERT_EQ(back.rect(), film.rect());
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 7; ++x) {
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(back.rgba(x, y)[c], film.rgba(x, y)[c], 1e-3f);
      EXPECT_EQ(back.depth(x, y), film.depth(x, y));  // float: exact, +inf kept
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.normal(x, y)[c], film.normal(x, y)[c], 1e-3f);
      EXPECT_NEAR(back.albedo(x, y).x, 0.8f, 1e-3f);
      EXPECT_EQ(back.bvh_cost(x, y), film.bvh_cost(x, y));
      // float even in a half file: bit-exact
      EXPECT_EQ(std::memcmp(&back.variance(x, y), &film.variance(x, y), sizeof(glm::vec3)), 0) << x << "," << y;
    }
  }
}

TEST_F(ImageIoTest, ExrFloatOptionStoresColourExactly) {
  const TileBuffer film = sample_film();
  const fs::path file = dir_ / "film32.exr";
  write_exr(film, file, ExrPixelType::Float);
  const TileBuffer back = read_exr(file);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) EXPECT_EQ(back.rgba(x, y), film.rgba(x, y));
}

TEST_F(ImageIoTest, ExrOfATileKeepsItsPlaceInTheFrame) {
  TileBuffer tile(Rect{32, 64, 40, 70}, AovSet{});
  tile.rgba(35, 66) = {1, 2, 3, 1};
  const fs::path file = dir_ / "tile.exr";
  write_exr(tile, file);
  const TileBuffer back = read_exr(file);
  EXPECT_EQ(back.rect(), tile.rect());
  EXPECT_EQ(back.rgba(35, 66), glm::vec4(1, 2, 3, 1));
}

TEST(Srgb, TransferFunctionMatchesTheStandardAndClamps) {
  EXPECT_EQ(linear_to_srgb(0.0f), 0.0f);
  EXPECT_NEAR(linear_to_srgb(1.0f), 1.0f, 1e-6f);
  EXPECT_NEAR(linear_to_srgb(0.5f), 0.735357f, 1e-5f);
  EXPECT_NEAR(linear_to_srgb(0.002f), 0.02584f, 1e-5f);  // linear toe
  EXPECT_EQ(to_srgb8(7.0f), 255);
  EXPECT_EQ(to_srgb8(-1.0f), 0);
  EXPECT_EQ(to_srgb8(std::nanf("")), 0);
}

// Previews are encoded by table (fast); every code must still be to_srgb8's. Floats in [0, 1]
// are sampled every 997th bit pattern, and wherever the code changes between two samples every
// float between them is checked: each step of the table, exhaustively around it.
TEST(Srgb, PreviewEncodingIsToSrgb8ForEveryFloatAroundEachStep) {
  const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
  std::vector<float> values;
  std::uint32_t previous = 0;
  for (std::uint32_t bits = 0; bits <= one; bits += 997) {
    if (to_srgb8(std::bit_cast<float>(bits)) != to_srgb8(std::bit_cast<float>(previous))) {
      for (std::uint32_t b = previous; b <= bits; ++b) values.push_back(std::bit_cast<float>(b));
    } else {
      values.push_back(std::bit_cast<float>(bits));
    }
    previous = bits;
  }
  for (float v : {1.0f, 2.0f, -0.5f, 0.0f, -0.0f, std::numeric_limits<float>::infinity(),
                  -std::numeric_limits<float>::infinity(), std::nanf("")}) {
    values.push_back(v);
  }
  const int width = 1024;
  const int height = static_cast<int>((values.size() + width - 1) / width);
  TileBuffer film(Rect{0, 0, width, height}, AovSet{});
  for (std::size_t i = 0; i < values.size(); ++i) {
    film.rgba(static_cast<int>(i % width), static_cast<int>(i / width)) = glm::vec4(values[i], values[i], values[i], 1.0f);
  }
  const Rgb8Image encoded = to_srgb8_image(film);
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (encoded.pixels[3 * i] != to_srgb8(values[i])) ++mismatches;
  }
  EXPECT_EQ(mismatches, 0u) << "of " << values.size() << " values";
  EXPECT_GT(values.size(), 1'000'000u);
}

TEST_F(ImageIoTest, FailedWriteLeavesNeitherTargetNorTemporaryFile) {
  const fs::path target = dir_ / "never.exr";
  EXPECT_THROW(write_file_atomically(target,
                                     [](const fs::path& temp) {
                                       std::FILE* f = std::fopen(temp.c_str(), "w");
                                       std::fputs("partial", f);
                                       std::fclose(f);
                                       throw std::runtime_error("disk full");
                                     }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir_.path()));
}

TEST(PreviewFormat, UnknownExtensionIsReportedBeforeRendering) {
  EXPECT_TRUE(preview_format_supported("x.png"));
  EXPECT_TRUE(preview_format_supported("x.jpg"));
  EXPECT_FALSE(preview_format_supported("x.notanimage"));
}

TEST(PreviewFormat, PngAndJpegByTheirExtensionsInAnyCase) {
  for (const char* name : {"x.PNG", "x.jpeg", "x.JPG", "x.jpe", "x.jif", "x.jfif", "x.jfi", "a.b/x.png"}) {
    EXPECT_TRUE(preview_format_supported(name)) << name;
  }
  for (const char* name : {"x.exr", "x.tif", "png", "x.png.part", "x"}) EXPECT_FALSE(preview_format_supported(name)) << name;
}

TEST_F(ImageIoTest, FileWriterErrorsLeaveNeitherTargetNorTemporaryFile) {
  const fs::path target = dir_ / "never.png";
  EXPECT_THROW(write_c_file_atomically(target,
                                       [](std::FILE* out) {
                                         std::fputs("partial", out);
                                         throw std::runtime_error("disk full");
                                       }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir_.path()));
}

TEST_F(ImageIoTest, FileWriterRenamesWhatItWroteOntoTheTarget) {
  const fs::path target = dir_ / "sub" / "done.png";
  write_c_file_atomically(target, [](std::FILE* out) { std::fputs("bytes", out); });
  EXPECT_EQ(fs::file_size(target), 5u);
  EXPECT_EQ(std::distance(fs::directory_iterator(target.parent_path()), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace farm
