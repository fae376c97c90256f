// The PNG and JPEG writers' error paths: a libpng or libjpeg error becomes an exception that
// names the file, rather than a longjmp into nowhere or libjpeg's exit(). Their output is read
// back with OpenImageIO in tests/oiio/. And a preview streamed row by row (StreamedPreview) is the
// same file as one written whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <thread>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/image/jpeg_writer.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/preview.h"
#include "renderer/image/rgb8_image.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

struct CloseFile {
  void operator()(std::FILE* file) const { std::fclose(file); }
};
using File = std::unique_ptr<std::FILE, CloseFile>;

// Big and noisy enough that the encoders write to the file (and hit its error) before they end.
Rgb8Image noise(int width, int height) {
  Rgb8Image image{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width * height * 3))};
  std::uint32_t state = 12345;
  for (std::uint8_t& v : image.pixels) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<std::uint8_t>(state >> 24);
  }
  return image;
}

// Writing to /dev/full fails with ENOSPC, as on a full disk.
File full_device() {
  if (!fs::exists("/dev/full")) return nullptr;
  return File(std::fopen("/dev/full", "wb"));
}

template <typename Write>
std::string error_of(Write write) {
  try {
    write();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

struct Writer {
  const char* format;  // as the writer's messages name it
  void (*write)(const Rgb8Image&, std::FILE*, const fs::path&);
};

class PreviewWriters : public ::testing::TestWithParam<Writer> {};

TEST_P(PreviewWriters, AnErrorOfTheLibraryIsAnExceptionNamingTheFile) {
  File out(std::tmpfile());
  ASSERT_TRUE(out);
  // An image without pixels: libpng refuses its header, libjpeg the empty image.
  const std::string error = error_of([&] { GetParam().write(Rgb8Image{}, out.get(), "renders/empty"); });
  EXPECT_NE(error.find(std::string("renders/empty: cannot write ") + GetParam().format + ": "), std::string::npos)
      << error;
}

TEST_P(PreviewWriters, AFullDiskIsAnExceptionNamingTheFile) {
  File out = full_device();
  if (!out) GTEST_SKIP() << "no /dev/full";
  const std::string error = error_of([&] { GetParam().write(noise(512, 512), out.get(), "renders/big"); });
  EXPECT_NE(error.find(std::string("renders/big: cannot write ") + GetParam().format + ": "), std::string::npos)
      << error;
}

INSTANTIATE_TEST_SUITE_P(PngAndJpeg, PreviewWriters,
                         ::testing::Values(Writer{"PNG", write_png}, Writer{"JPEG", write_jpeg}),
                         [](const ::testing::TestParamInfo<Writer>& p) { return std::string(p.param.format); });

}  // namespace
}  // namespace farm

namespace farm {
namespace {

std::string file_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TileBuffer gradient_film(const Rect& rect) {
  TileBuffer film(rect, AovSet{});
  for (int y = rect.y0; y < rect.y1; ++y) {
    for (int x = rect.x0; x < rect.x1; ++x) {
      film.rgba(x, y) = {static_cast<float>(x) / 97.0f, static_cast<float>(y % 13) / 13.0f, x % 7 == 0 ? 2.0f : 0.1f, 1.0f};
    }
  }
  return film;
}

// Rows converted out of order, by several threads, in pieces of any size (as the EXR's chunk
// packers hand them over) make the same file, byte for byte, as write_preview, for both formats,
// also for a film that does not start at the origin.
TEST(StreamedPreview, RowsConvertedInAnyOrderByManyThreadsMakeWritePreviewsFile) {
  test::TempDir dir;
  const TileBuffer film = gradient_film(Rect{5, 9, 5 + 203, 9 + 150});
  for (const std::string name : {"p.png", "p.jpg"}) {
    write_preview(film, dir / ("whole-" + name));
    StreamedPreview streamed(film, dir / ("streamed-" + name));
    std::thread writer([&] { streamed.finish(); });
    // Pieces of 16 lines (the last short), from the bottom up, two threads taking turns.
    std::vector<std::pair<int, int>> pieces;
    for (int y = 0; y < 150; y += 16) pieces.emplace_back(y, std::min(150, y + 16));
    std::reverse(pieces.begin(), pieces.end());
    std::thread a([&] {
      for (std::size_t i = 0; i < pieces.size(); i += 2) streamed.convert(pieces[i].first, pieces[i].second);
    });
    std::thread b([&] {
      for (std::size_t i = 1; i < pieces.size(); i += 2) streamed.convert(pieces[i].first, pieces[i].second);
    });
    a.join();
    b.join();
    writer.join();
    EXPECT_EQ(file_bytes(dir / ("streamed-" + name)), file_bytes(dir / ("whole-" + name))) << name;
  }
}

// Rows that never come (the EXR beside it failed): the writer stops, throws, and leaves no file,
// for both formats.
TEST(StreamedPreview, AnAbandonedPreviewThrowsAndLeavesNoFile) {
  for (const std::string name : {"p.png", "p.jpg"}) {
    test::TempDir dir;
    const TileBuffer film = gradient_film(Rect{0, 0, 64, 48});
    StreamedPreview streamed(film, dir / name);
    streamed.convert(0, 16);
    std::exception_ptr failure;
    std::thread writer([&] {
      try {
        streamed.finish();
      } catch (...) {
        failure = std::current_exception();
      }
    });
    streamed.abandon();
    writer.join();
    ASSERT_TRUE(failure) << name;
    EXPECT_THROW(std::rethrow_exception(failure), std::runtime_error) << name;
    EXPECT_TRUE(fs::is_empty(dir.path())) << name;
  }
}

}  // namespace
}  // namespace farm
