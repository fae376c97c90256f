// Textures on their own: filtering, wrap modes and mips against values worked out by hand, every
// file kind decoded to the expected linear values, sizes refused from the header, and the
// process's cache decoding each file once.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "renderer/compare/image.h"
#include "renderer/image/png_writer.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/texture/texture_file.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// A 4x4 texture whose texel (i, j) is (i, j, i + 4j, 1): every texel tells where it is.
Texture numbered_4x4() {
  std::vector<glm::vec4> texels;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) texels.emplace_back(i, j, i + 4 * j, 1);
  return Texture(4, 4, std::move(texels));
}

TEST(TextureSampling, BilinearReturnsTexelsAtTheirCentresAndMeansBetweenThem) {
  const Texture t = numbered_4x4();
  const TextureSampler clamp{TextureWrap::ClampToEdge, TextureWrap::ClampToEdge};
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      EXPECT_EQ(t.sample({(i + 0.5f) / 4, (j + 0.5f) / 4}, clamp), t.texel(0, i, j)) << i << "," << j;
    }
  // Halfway between texels (1, 2) and (2, 2): their mean.
  EXPECT_EQ(t.sample({0.5f, 2.5f / 4}, clamp), glm::vec4(1.5f, 2, 9.5f, 1));
  // A quarter of the way from (0, 0) towards (1, 1) diagonally: weights 9/16, 3/16, 3/16, 1/16.
  EXPECT_EQ(t.sample({0.1875f, 0.1875f}, clamp), glm::vec4(0.25f, 0.25f, 1.25f, 1));
}

TEST(TextureSampling, WrapModesPickTheTexelsGltfSays) {
  const Texture t = numbered_4x4();
  const auto column = [&](float u, TextureWrap wrap) {
    TextureSampler s{wrap, TextureWrap::ClampToEdge, TextureFilter::Nearest, TextureFilter::Nearest};
    return static_cast<int>(t.sample({u, 0.1f}, s).x);
  };
  // u = -0.1 is texel -1 (floor of -0.4), 1.1 texel 4, 2.3 texel 9.
  EXPECT_EQ(column(-0.1f, TextureWrap::Repeat), 3);
  EXPECT_EQ(column(1.1f, TextureWrap::Repeat), 0);
  EXPECT_EQ(column(2.3f, TextureWrap::Repeat), 1);
  EXPECT_EQ(column(-0.1f, TextureWrap::ClampToEdge), 0);
  EXPECT_EQ(column(1.1f, TextureWrap::ClampToEdge), 3);
  EXPECT_EQ(column(2.3f, TextureWrap::ClampToEdge), 3);
  // Mirrored: ... 1 0 | 0 1 2 3 | 3 2 1 0 | 0 1 ...
  EXPECT_EQ(column(-0.1f, TextureWrap::MirroredRepeat), 0);
  EXPECT_EQ(column(1.1f, TextureWrap::MirroredRepeat), 3);
  EXPECT_EQ(column(2.3f, TextureWrap::MirroredRepeat), 1);
  // Coordinates that are not numbers read somewhere, never out of bounds.
  const TextureSampler repeat;
  EXPECT_TRUE(std::isfinite(t.sample({NAN, INFINITY}, repeat).x));
  EXPECT_TRUE(std::isfinite(t.sample({1e30f, -1e30f}, repeat, 1e30f).x));
}

TEST(TextureSampling, MipsAreBoxAveragesAndAWholeTextureFootprintReadsTheMean) {
  const Texture t = numbered_4x4();
  ASSERT_EQ(t.levels(), 3);  // 4x4, 2x2, 1x1
  EXPECT_EQ(t.level_width(1), 2);
  EXPECT_EQ(t.texel(1, 1, 0), glm::vec4(2.5f, 0.5f, 4.5f, 1));  // texels (2..3, 0..1)
  EXPECT_EQ(t.texel(2, 0, 0), glm::vec4(1.5f, 1.5f, 7.5f, 1));  // the mean of all
  const TextureSampler s;
  // One pixel covering the whole texture (footprint 1): the last level.
  EXPECT_EQ(t.sample({0.3f, 0.7f}, s, 1.0f), glm::vec4(1.5f, 1.5f, 7.5f, 1));
  // Half the texture (lod 1): level 1 read bilinearly, at its texel (0, 0)'s centre.
  EXPECT_EQ(t.sample({0.25f, 0.25f}, s, 0.5f), t.texel(1, 0, 0));
  // Without mipmaps the same footprint reads level 0.
  TextureSampler flat;
  flat.mipmaps = false;
  EXPECT_EQ(t.sample({0.125f, 0.125f}, flat, 1.0f), t.texel(0, 0, 0));
  // An odd side: 3x3 gives 1x1 next, its texels clamped at the edge.
  const Texture odd(3, 3, std::vector<glm::vec4>(9, glm::vec4(2.0f)));
  EXPECT_EQ(odd.levels(), 2);
  EXPECT_EQ(odd.texel(1, 0, 0), glm::vec4(2.0f));
}

TEST(TextureSampling, KhrTextureTransformMovesRotatesAndScalesAsTheSpecSays) {
  // Scale first, then rotate (counter-clockwise in uv by the spec's matrix), then offset.
  const glm::mat3 m = uv_transform({0.5f, 0.25f}, static_cast<float>(M_PI / 2), {2.0f, 1.0f});
  const glm::vec3 p = m * glm::vec3(1.0f, 0.0f, 1.0f);
  // (1, 0) scaled to (2, 0); the spec's rotation [[c, s], [-s, c]] at 90 degrees gives (0, -2);
  // offset: (0.5, -1.75).
  EXPECT_NEAR(p.x, 0.5f, 1e-6f);
  EXPECT_NEAR(p.y, -1.75f, 1e-6f);
}

void write_png_bytes(const fs::path& file, int width, int height, const std::vector<std::uint8_t>& rgb) {
  Rgb8Image image;
  image.width = width;
  image.height = height;
  image.pixels = rgb;
  std::FILE* out = std::fopen(file.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  write_png(image, out, file);
  std::fclose(out);
}

TEST(TextureFiles, EightBitColourIsSrgbDecodedAndDataIsReadAsStored) {
  TempDir dir;
  write_png_bytes(dir / "grey.png", 1, 1, {128, 0, 255});
  const auto colour = load_texture_file(dir / "grey.png", TextureColourSpace::Srgb);
  EXPECT_NEAR(colour->texel(0, 0, 0).x, 0.21586f, 1e-5f);
  EXPECT_EQ(colour->texel(0, 0, 0).y, 0.0f);
  EXPECT_EQ(colour->texel(0, 0, 0).z, 1.0f);
  EXPECT_EQ(colour->texel(0, 0, 0).w, 1.0f);
  const auto data = load_texture_file(dir / "grey.png", TextureColourSpace::Linear);
  EXPECT_FLOAT_EQ(data->texel(0, 0, 0).x, 128.0f / 255.0f);
}

TEST(TextureFiles, AnExrKeepsItsLinearValuesInEitherSpace) {
  TempDir dir;
  Image image = make_image(2, 1, {"R", "G", "B"});
  image.values = {0.5f, 2.0f, 0.25f, 10.0f, 0.0f, 0.125f};
  write_exr_image(image, dir / "light.exr");
  const auto t = load_texture_file(dir / "light.exr", TextureColourSpace::Srgb);
  EXPECT_EQ(t->texel(0, 0, 0), glm::vec4(0.5f, 2.0f, 0.25f, 1.0f));
  EXPECT_EQ(t->texel(0, 1, 0), glm::vec4(10.0f, 0.0f, 0.125f, 1.0f));
}

// A Radiance file: header, resolution, then `body`.
fs::path write_hdr(const TempDir& dir, const std::string& name, int width, int height, const std::string& body) {
  return dir.write(name, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " + std::to_string(height) + " +X " +
                             std::to_string(width) + "\n" + body);
}

TEST(TextureFiles, RadianceHdrDecodesFlatAndRunLengthScanlines) {
  TempDir dir;
  // Flat: two pixels, (128, 64, 32) at exponent 129 is (1, 0.5, 0.25); exponent 0 is black.
  const std::string flat{'\x80', '\x40', '\x20', '\x81', '\x10', '\x10', '\x10', '\x00'};
  const auto a = load_texture_file(write_hdr(dir, "flat.hdr", 2, 1, flat), TextureColourSpace::Srgb);
  EXPECT_EQ(a->texel(0, 0, 0), glm::vec4(1.0f, 0.5f, 0.25f, 1.0f));
  EXPECT_EQ(a->texel(0, 1, 0), glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
  // Run-length: 8 pixels; R a run of 8 x 128, G literals 0..7 x 16, B a run of 8 x 0, E 8 x 130.
  std::string rle{'\x02', '\x02', '\x00', '\x08'};
  rle += std::string{'\x88', '\x80'};
  rle += '\x08';
  for (int k = 0; k < 8; ++k) rle += static_cast<char>(16 * k);
  rle += std::string{'\x88', '\x00', '\x88', '\x82'};
  const auto b = load_texture_file(write_hdr(dir, "rle.hdr", 8, 1, rle), TextureColourSpace::Srgb);
  for (int x = 0; x < 8; ++x) EXPECT_EQ(b->texel(0, x, 0), glm::vec4(2.0f, 16 * x / 64.0f, 0.0f, 1.0f)) << x;
  // Cut short, or a run past the row: errors naming the file.
  for (const std::string& bad : {rle.substr(0, 10), std::string{'\x02', '\x02', '\x00', '\x08', '\x89', '\x01'}}) {
    try {
      load_texture_file(write_hdr(dir, "bad.hdr", 8, 1, bad), TextureColourSpace::Srgb);
      FAIL() << "decoded a malformed HDR";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.hdr"), std::string::npos) << e.what();
    }
  }
}

// A PNG's signature and IHDR claiming `width` x `height`, and nothing after.
fs::path png_header_only(const TempDir& dir, const std::string& name, std::uint32_t width, std::uint32_t height) {
  std::string bytes = "\x89PNG\r\n\x1a\n";
  bytes += std::string("\0\0\0\x0dIHDR", 8);
  for (std::uint32_t v : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes += static_cast<char>((v >> shift) & 0xff);
  }
  bytes += std::string("\x08\x02\0\0\0\0\0\0\0", 9);
  return dir.write(name, bytes);
}

TEST(TextureFiles, ATextureLargerThanTheLimitIsRefusedFromItsHeader) {
  TempDir dir;
  for (const auto& [width, height] : {std::pair{20000u, 20000u}, std::pair{9000u, 9000u}}) {
    const fs::path file = png_header_only(dir, "huge" + std::to_string(width) + ".png", width, height);
    try {
      load_texture_file(file, TextureColourSpace::Srgb);
      FAIL() << "no error for " << width;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file.filename().string()), std::string::npos) << what;
      EXPECT_NE(what.find(std::to_string(width) + "x" + std::to_string(height)), std::string::npos) << what;
      EXPECT_NE(what.find("not decoded"), std::string::npos) << what;
    }
  }
  const fs::path hdr = write_hdr(dir, "huge.hdr", 100000, 2, "");
  EXPECT_THROW(load_texture_file(hdr, TextureColourSpace::Srgb), InputError);
}

TEST(TextureCacheTest, DecodesAFileOnceWhileHeldAndAgainWhenChangedOrReleased) {
  TempDir dir;
  write_png_bytes(dir / "t.png", 2, 1, {10, 20, 30, 40, 50, 60});
  TextureCache cache;
  std::vector<std::shared_ptr<const Texture>> held(8);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < held.size(); ++i) {
    threads.emplace_back([&, i] { held[i] = cache.get(dir / "t.png", TextureColourSpace::Srgb); });
  }
  for (std::thread& t : threads) t.join();
  for (int i = 0; i < 100; ++i) EXPECT_EQ(cache.get(dir / "t.png", TextureColourSpace::Srgb), held[0]);
  for (const auto& h : held) EXPECT_EQ(h, held[0]);
  EXPECT_EQ(cache.decodes(), 1u);
  // Another colour space is another texture.
  const auto data = cache.get(dir / "t.png", TextureColourSpace::Linear);
  EXPECT_NE(data, held[0]);
  EXPECT_EQ(cache.decodes(), 2u);
  // Rewritten (another size): decoded again.
  write_png_bytes(dir / "t.png", 1, 1, {255, 255, 255});
  std::shared_ptr<const Texture> changed = cache.get(dir / "t.png", TextureColourSpace::Srgb);
  EXPECT_EQ(changed->width(), 1);
  EXPECT_EQ(cache.decodes(), 3u);
  // Once nobody holds it, it is gone: the next caller decodes it again.
  const std::weak_ptr<const Texture> weak = changed;
  changed.reset();
  EXPECT_TRUE(weak.expired());
  cache.get(dir / "t.png", TextureColourSpace::Srgb);
  EXPECT_EQ(cache.decodes(), 4u);
  // A file that fails is tried again by the next caller.
  EXPECT_THROW(cache.get(dir / "missing.png", TextureColourSpace::Srgb), InputError);
  EXPECT_THROW(cache.get(dir / "missing.png", TextureColourSpace::Srgb), InputError);
  EXPECT_EQ(cache.decodes(), 6u);
}

}  // namespace
}  // namespace farm
