// Reads previews (written with libpng and libjpeg) back with OpenImageIO, a reader independent of
// those writers. A test binary of its own: linking OpenImageIO into farm_tests would add its 0.3 s
// of library loading to every one of that binary's test processes.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/image/preview.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct ReadBack {
  int width = 0, height = 0, channels = 0;
  std::string format;      // OpenImageIO's name for the file's format
  std::string colorspace;  // as the file declares it
  std::vector<unsigned char> pixels;
};

ReadBack read_back(const fs::path& file) {
  auto in = OIIO::ImageInput::open(file.string());
  if (!in) throw std::runtime_error(OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  ReadBack r{spec.width, spec.height, spec.nchannels, in->format_name(),
             spec.get_string_attribute("oiio:ColorSpace"), {}};
  r.pixels.resize(static_cast<std::size_t>(r.width * r.height * r.channels));
  if (!in->read_image(0, 0, 0, r.channels, OIIO::TypeDesc::UINT8, r.pixels.data())) {
    throw std::runtime_error(in->geterror());
  }
  return r;
}

// What the writers are handed: the film's RGB through to_srgb8, rows top to bottom.
std::vector<unsigned char> expected_pixels(const TileBuffer& film) {
  std::vector<unsigned char> pixels;
  const Rect& r = film.rect();
  for (int y = r.y0; y < r.y1; ++y) {
    for (int x = r.x0; x < r.x1; ++x) {
      for (int c = 0; c < 3; ++c) pixels.push_back(to_srgb8(film.rgba(x, y)[c]));
    }
  }
  return pixels;
}

TEST(PreviewPng, IsSrgbEncodedAndClamped) {
  test::TempDir dir;
  TileBuffer film(Rect{0, 0, 4, 2}, AovSet{});
  film.rgba(0, 0) = {0.5f, 0.0f, 3.0f, 1.0f};
  film.rgba(3, 1) = {0.0f, 1.0f, -2.0f, 1.0f};
  const fs::path file = dir / "preview.png";
  write_preview(film, file);
  auto in = OIIO::ImageInput::open(file.string());
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().width, 4);
  EXPECT_EQ(in->spec().height, 2);
  ASSERT_EQ(in->spec().nchannels, 3);
  std::vector<unsigned char> pixels(4 * 2 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data()));
  EXPECT_EQ(pixels[0], 188);  // 0.5 linear -> 0.7354 sRGB
  EXPECT_EQ(pixels[1], 0);
  EXPECT_EQ(pixels[2], 255);  // 3.0 clamps
  const std::size_t last = (1 * 4 + 3) * 3;  // bottom row, last pixel: rows stay top to bottom
  EXPECT_EQ(pixels[last], 0);
  EXPECT_EQ(pixels[last + 1], 255);
  EXPECT_EQ(pixels[last + 2], 0);  // negative clamps to 0
}

TEST(PreviewPng, HoldsExactlyTheEightBitValuesOfAFilmThatCoversTheRange) {
  test::TempDir dir;
  // Odd sizes, a film not at the origin, values across the whole range and beyond it.
  const Rect rect{3, 5, 3 + 257, 5 + 31};
  TileBuffer film(rect, AovSet{});
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      const float u = static_cast<float>(x - rect.x0) / 255.0f;
      const float v = static_cast<float>(y - rect.y0) / 30.0f;
      film.rgba(x, y) = {u * u * u, 1.1f * v - 0.05f, std::fmod(u * 7.0f + v, 1.0f), 1.0f};
    }
  }
  const fs::path file = dir / "gradient.png";
  write_preview(film, file);
  const ReadBack r = read_back(file);
  EXPECT_EQ(r.format, "png");
  EXPECT_EQ(r.colorspace, "sRGB");
  EXPECT_EQ(r.width, 257);
  EXPECT_EQ(r.height, 31);
  ASSERT_EQ(r.channels, 3);
  EXPECT_EQ(r.pixels, expected_pixels(film));
}

TEST(PreviewJpeg, HasTheSizeAndTheColoursWithinASmallTolerance) {
  test::TempDir dir;
  TileBuffer film(Rect{0, 0, 120, 80}, AovSet{});
  for (int y = 0; y < 80; ++y) {
    // Clear of the sRGB curve's steep toe, where a neighbour's light pulls a dark pixel far up.
    for (int x = 0; x < 120; ++x) film.rgba(x, y) = {0.05f + 0.95f * x / 119.0f, 0.05f + 0.95f * y / 79.0f, 0.25f, 1.0f};
  }
  const fs::path file = dir / "preview.jpg";
  write_preview(film, file);
  const ReadBack r = read_back(file);
  EXPECT_EQ(r.format, "jpeg");
  EXPECT_EQ(r.width, 120);
  EXPECT_EQ(r.height, 80);
  ASSERT_EQ(r.channels, 3);
  const std::vector<unsigned char> expected = expected_pixels(film);
  ASSERT_EQ(r.pixels.size(), expected.size());
  int worst = 0;
  double sum = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const int d = std::abs(int(r.pixels[i]) - int(expected[i]));
    worst = std::max(worst, d);
    sum += d;
  }
  // Quality 98 with 4:2:0 chroma on a smooth image: a few levels off at most (6 here, as when
  // OpenImageIO wrote previews), less than one on average.
  EXPECT_LE(worst, 8);
  EXPECT_LT(sum / static_cast<double>(expected.size()), 1.0);
}

TEST(PreviewJpeg, EveryJpegExtensionInAnyCaseWritesAJpegAndPngAPng) {
  test::TempDir dir;
  TileBuffer film(Rect{0, 0, 9, 7}, AovSet{});
  for (const std::string name : {"a.jpg", "b.JPEG", "c.jpe", "d.jif", "e.jfif", "f.jfi", "g.PNG"}) {
    const fs::path file = dir / name;
    write_preview(film, file);
    const ReadBack r = read_back(file);
    EXPECT_EQ(r.format, name == "g.PNG" ? "png" : "jpeg") << name;
    EXPECT_EQ(r.width, 9) << name;
    EXPECT_EQ(r.height, 7) << name;
  }
}

TEST(PreviewPng, AnUnknownFormatNamesTheFileAndLeavesNothing) {
  test::TempDir dir;
  TileBuffer film(Rect{0, 0, 2, 2}, AovSet{});
  const fs::path file = dir / "preview.notanimage";
  try {
    write_preview(film, file);
    FAIL() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no image writer"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace farm
