// The PNGs written here (renderer/image/png_strips.h), read back by libpng (read_png), which
// checks every chunk's CRC and the zlib stream's checksum: each pixel as written, for sizes that
// leave a short last strip, a single row or column, and strips compressed out of order by
// several threads.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

#include "renderer/image/png_reader.h"
#include "renderer/image/png_strips.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/rgb8_image.h"

namespace farm {
namespace {

struct CloseFile {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, CloseFile>;

// A background with edges and noise, as a preview has.
Rgb8Image picture(int width, int height) {
  Rgb8Image image{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height * 3)};
  std::uint32_t state = 7;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      std::uint8_t* p = &image.pixels[(static_cast<std::size_t>(y) * width + x) * 3];
      state = state * 1664525u + 1013904223u;
      const bool inside = (x - width / 2) * (x - width / 2) + (y - height / 2) * (y - height / 2) < width * height / 8;
      p[0] = inside ? static_cast<std::uint8_t>(state >> 24) : 100;
      p[1] = static_cast<std::uint8_t>(x * 255 / std::max(1, width - 1));
      p[2] = static_cast<std::uint8_t>(y * 7);
    }
  }
  return image;
}

std::vector<std::uint8_t> read_back(std::FILE* file, int width, int height) {
  std::rewind(file);
  const DecodedImage decoded = read_png(file, "test.png", 1 << 16);
  EXPECT_EQ(decoded.width, width);
  EXPECT_EQ(decoded.height, height);
  EXPECT_EQ(decoded.channels, 3);
  std::vector<std::uint8_t> bytes;
  for (float v : decoded.values) bytes.push_back(static_cast<std::uint8_t>(v * 255.0f + 0.5f));
  return bytes;
}

TEST(PngStrips, LibpngReadsBackEveryPixelWhateverTheSize) {
  for (const auto& [width, height] : {std::pair{1, 1}, std::pair{1, 40}, std::pair{300, 1}, std::pair{7, 16},
                                     std::pair{64, 17}, std::pair{203, 150}}) {
    const Rgb8Image image = picture(width, height);
    File file(std::tmpfile());
    ASSERT_TRUE(file);
    write_png(image, file.get(), "test.png");
    EXPECT_EQ(read_back(file.get(), width, height), image.pixels) << width << "x" << height;
  }
}

TEST(PngStrips, StripsCompressedOutOfOrderOnManyThreadsMakeTheSameFile) {
  const Rgb8Image image = picture(151, 121);  // 8 strips, the last of 9 rows
  const auto row = [&](int y) { return image.pixels.data() + static_cast<std::size_t>(y) * 151 * 3; };
  File serial(std::tmpfile());
  write_png(image, serial.get(), "test.png");
  PngStrips png(151, 121, "test.png");
  ASSERT_EQ(png.strips(), 8);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) {
    threads.emplace_back([&, t] {
      for (int k = png.strips() - 1 - t; k >= 0; k -= 3) png.compress(k, row);
    });
  }
  for (std::thread& t : threads) t.join();
  File parallel(std::tmpfile());
  png.write(parallel.get());
  const auto bytes_of = [](std::FILE* f) {
    std::fflush(f);
    std::rewind(f);
    std::vector<std::uint8_t> out;
    for (int c; (c = std::fgetc(f)) != EOF;) out.push_back(static_cast<std::uint8_t>(c));
    return out;
  };
  EXPECT_EQ(bytes_of(parallel.get()), bytes_of(serial.get()));
  EXPECT_EQ(read_back(parallel.get(), 151, 121), image.pixels);
}

}  // namespace
}  // namespace farm
