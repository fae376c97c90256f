#include <gtest/gtest.h>
#include <zlib.h>

#include <bit>
#include <limits>

#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <glm/geometric.hpp>
#include <ImfInputFile.h>
#include <ImfFrameBuffer.h>
#include <ImfOutputFile.h>
#include <Imath/half.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <vector>
#include <iterator>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>

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

// The same film written by OpenEXR's own C++ writer (ZIP at zlib level 1, the channels as
// write_exr types them), as write_exr wrote it before it packed its chunks itself.
void write_with_openexr(const TileBuffer& film, const fs::path& file) {
  const Rect& r = film.rect();
  const Imath::Box2i window({r.x0, r.y0}, {r.x1 - 1, r.y1 - 1});
  Imf::Header header(window, window);
  header.compression() = Imf::ZIP_COMPRESSION;
  header.zipCompressionLevel() = 1;
  Imf::FrameBuffer frame;
  std::vector<std::vector<Imath::half>> halves;
  std::vector<std::vector<float>> floats;
  const auto add = [&](const char* name, bool as_float, auto value) {
    const std::ptrdiff_t origin = static_cast<std::ptrdiff_t>(r.y0) * r.width() + r.x0;
    header.channels().insert(name, Imf::Channel(as_float ? Imf::FLOAT : Imf::HALF));
    if (as_float) {
      std::vector<float>& plane = floats.emplace_back();
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) plane.push_back(value(x, y));
      frame.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(plane.data() - origin), sizeof(float),
                                    sizeof(float) * static_cast<std::size_t>(r.width())));
    } else {
      std::vector<Imath::half>& plane = halves.emplace_back();
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) plane.push_back(Imath::half(value(x, y)));
      frame.insert(name, Imf::Slice(Imf::HALF, reinterpret_cast<char*>(plane.data() - origin), sizeof(Imath::half),
                                    sizeof(Imath::half) * static_cast<std::size_t>(r.width())));
    }
  };
  const char* rgba[] = {"R", "G", "B", "A"};
  for (int c = 0; c < 4; ++c) add(rgba[c], false, [&](int x, int y) { return film.rgba(x, y)[c]; });
  const AovSet& aovs = film.aovs();
  if (aovs.depth) add("Z", true, [&](int x, int y) { return film.depth(x, y); });
  const char* n[] = {"N.X", "N.Y", "N.Z"};
  const char* a[] = {"albedo.R", "albedo.G", "albedo.B"};
  const char* v[] = {"variance.R", "variance.G", "variance.B"};
  for (int c = 0; c < 3; ++c) {
    if (aovs.normal) add(n[c], false, [&](int x, int y) { return film.normal(x, y)[c]; });
    if (aovs.albedo) add(a[c], false, [&](int x, int y) { return film.albedo(x, y)[c]; });
    if (aovs.variance) add(v[c], true, [&](int x, int y) { return film.variance(x, y)[c]; });
  }
  if (aovs.bvh_cost) add("bvh_cost", true, [&](int x, int y) { return film.bvh_cost(x, y); });
  Imf::OutputFile out(file.c_str(), header);
  out.setFrameBuffer(frame);
  out.writePixels(r.height());
}

// Each chunk's bytes as stored in the file (compressed, or raw when zlib did not shrink it).
std::vector<std::string> raw_chunks(const fs::path& file) {
  Imf::InputFile in(file.c_str());
  const Imath::Box2i dw = in.header().dataWindow();
  std::vector<std::string> chunks;
  for (int y = dw.min.y; y <= dw.max.y; y += 16) {
    const char* data = nullptr;
    int size = 0;
    in.rawPixelData(y, data, size);
    chunks.emplace_back(data, static_cast<std::size_t>(size));
  }
  return chunks;
}

// A chunk as its lines were before the deflate: inflated by zlib, or as stored when raw (its size
// is then the lines' size).
std::string unpacked_chunk(const std::string& chunk, std::size_t lines_bytes) {
  if (chunk.size() == lines_bytes) return chunk;
  std::string out(lines_bytes, '\0');
  uLongf size = static_cast<uLongf>(out.size());
  EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(chunk.data()),
                       static_cast<uLong>(chunk.size())),
            Z_OK);
  EXPECT_EQ(size, lines_bytes);
  return out;
}

// write_exr packs its chunks itself (exr_zip_block.h): inflated, byte for byte what OpenEXR's own
// writer deflates (the same lines, split and predicted), stored raw exactly where OpenEXR stores
// them raw, and within a tenth of OpenEXR's size at zlib level 1 (ours are igzip's), on films of every
// shape a frame has: all the AOVs, a height that is no multiple of the chunk's 16 lines, an odd
// width, a film that does not start at the origin, and noise that deflate cannot shrink.
// write_exr packs its chunks on as many threads as it is given: every chunk on one thread when
// given one (`farm render --threads 1` compresses on one core, not on all), and the file is
// byte for byte the one all cores write.
TEST_F(ImageIoTest, ExrChunksArePackedOnTheThreadsAsked) {
  TileBuffer film(Rect{0, 0, 64, 200}, {});  // 13 chunks of 16 lines
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 64; ++x) film.rgba(x, y) = {0.01f * x, 0.005f * y, 0.25f, 1.0f};
  std::mutex mutex;
  std::set<std::thread::id> packers;
  int chunks = 0;
  write_exr(film, dir_ / "one.exr", ExrPixelType::Half,
            [&](int, int) {
              const std::lock_guard lock(mutex);
              packers.insert(std::this_thread::get_id());
              ++chunks;
            },
            1);
  EXPECT_EQ(chunks, 13);
  EXPECT_EQ(packers.size(), 1u);
  write_exr(film, dir_ / "all.exr", ExrPixelType::Half, {}, 0);
  const auto bytes = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(dir_ / "one.exr"), bytes(dir_ / "all.exr"));
}

TEST_F(ImageIoTest, ExrChunksInflateToThoseOfOpenExrsOwnWriter) {
  std::mt19937 rng(5);
  // Random bit patterns of finite halves and of floats: nothing for zlib. (No NaNs: a signalling
  // NaN is the one float whose half the F16C path and Imath's software tell apart.)
  std::uniform_int_distribution<std::uint32_t> bits;
  const auto noise = [&] {
    auto h = static_cast<std::uint16_t>(bits(rng) & 0xFFFFu);
    if ((h & 0x7C00u) == 0x7C00u) h = static_cast<std::uint16_t>(h & 0xFBFFu);
    Imath::half value;
    value.setBits(h);
    return static_cast<float>(value);
  };
  const auto float_noise = [&] { return std::bit_cast<float>(bits(rng)); };
  TileBuffer noisy(Rect{3, 40, 3 + 131, 40 + 37}, AovSet{.depth = true, .normal = false, .albedo = false,
                                                          .bvh_cost = false, .variance = false});
  TileBuffer smooth(Rect{0, 0, 257, 33}, AovSet{});
  for (int y = 0; y < 37; ++y) {
    for (int x = 0; x < 131; ++x) {
      noisy.rgba(3 + x, 40 + y) = {noise(), noise(), noise(), noise()};
      noisy.depth(3 + x, 40 + y) = float_noise();
    }
  }
  for (int y = 0; y < 33; ++y)
    for (int x = 0; x < 257; ++x) smooth.rgba(x, y) = {x / 257.0f, y / 33.0f, x > 100 ? 1.0f : 0.0f, 1.0f};
  int raw_chunks_seen = 0;
  for (const TileBuffer* film : {&noisy, &smooth}) {
    const TileBuffer sample = sample_film();
    for (const TileBuffer* f : {film, &sample}) {
      const fs::path ours = dir_ / "ours.exr", theirs = dir_ / "theirs.exr";
      write_exr(*f, ours);
      write_with_openexr(*f, theirs);
      const std::vector<std::string> a = raw_chunks(ours), b = raw_chunks(theirs);
      ASSERT_EQ(a.size(), b.size());
      const std::size_t line = static_cast<std::size_t>(f->rect().width()) *
                               (8 + (f->aovs().depth ? 4 : 0) + (f->aovs().normal ? 6 : 0) + (f->aovs().albedo ? 6 : 0) +
                                (f->aovs().bvh_cost ? 4 : 0) + (f->aovs().variance ? 12 : 0));
      std::size_t our_bytes = 0, their_bytes = 0;
      for (std::size_t c = 0; c < a.size(); ++c) {
        const std::size_t lines = std::min<std::size_t>(16, static_cast<std::size_t>(f->rect().height()) - 16 * c);
        const bool raw = a[c].size() == line * lines;
        EXPECT_EQ(raw, b[c].size() == line * lines) << "chunk " << c << " of " << a.size();
        EXPECT_EQ(unpacked_chunk(a[c], line * lines), unpacked_chunk(b[c], line * lines))
            << "chunk " << c << " of " << a.size();
        if (raw) ++raw_chunks_seen;
        our_bytes += a[c].size();
        their_bytes += b[c].size();
      }
      EXPECT_LE(our_bytes * 10, their_bytes * 11);  // tiny films: igzip 4% larger; a 1080p frame's 7% smaller
      // And the pixels read back are the film's, as the half channels round them.
      const TileBuffer back = read_exr(ours);
      ASSERT_EQ(back.rect(), f->rect());
      for (int y = f->rect().y0; y < f->rect().y1; ++y) {
        for (int x = f->rect().x0; x < f->rect().x1; ++x) {
          for (int c = 0; c < 4; ++c) {
            ASSERT_EQ(std::bit_cast<std::uint32_t>(back.rgba(x, y)[c]),
                      std::bit_cast<std::uint32_t>(static_cast<float>(Imath::half(f->rgba(x, y)[c]))));
          }
        }
      }
    }
  }
  EXPECT_GT(raw_chunks_seen, 0);  // the noise went in raw
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
                  -std::numeric_limits<float>::infinity(), std::nanf(""), -std::nanf(""),
                  std::bit_cast<float>(0x7F800001u), std::bit_cast<float>(0x80000001u),
                  std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min()}) {
    values.push_back(v);
  }
  // Each value in each channel (green and blue take the values one and two places on), rows of a
  // width that leaves the AVX2 encoder's groups of four a remainder of one.
  const int width = 1021;
  const int height = static_cast<int>((values.size() + width - 1) / width);
  TileBuffer film(Rect{0, 0, width, height}, AovSet{});
  const auto value = [&](std::size_t i) { return values[i % values.size()]; };
  for (std::size_t i = 0; i < static_cast<std::size_t>(width) * static_cast<std::size_t>(height); ++i) {
    film.rgba(static_cast<int>(i % width), static_cast<int>(i / width)) = glm::vec4(value(i), value(i + 1), value(i + 2), value(i + 3));
  }
  for (Srgb8Encoder encoder : {Srgb8Encoder::Best, Srgb8Encoder::Portable}) {
    const Rgb8Image encoded = to_srgb8_image(film, encoder);
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < encoded.pixels.size(); ++i) {
      if (encoded.pixels[i] != to_srgb8(value(i / 3 + i % 3))) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0u) << "of " << encoded.pixels.size() << " channels, encoder "
                              << (encoder == Srgb8Encoder::Best ? "best" : "portable");
  }
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
