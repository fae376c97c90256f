// The PNG and JPEG writers' error paths: a libpng or libjpeg error becomes an exception that
// names the file, rather than a longjmp into nowhere or libjpeg's exit(). Their output is read
// back with OpenImageIO in tests/oiio/.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/image/jpeg_writer.h"
#include "renderer/image/png_writer.h"
#include "renderer/image/rgb8_image.h"

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
