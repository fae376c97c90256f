// Reads previews back with OpenImageIO. A test binary of its own: linking OpenImageIO into
// farm_tests would add its 0.3 s of library loading to every one of that binary's test processes.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <filesystem>
#include <vector>

#include "renderer/image/preview.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

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
