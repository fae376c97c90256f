// The texture module against values worked out by hand, beyond texture_sampling_test.cpp: odd
// mip chains, trilinear and nearest level choice, filters per magnification, bilinear wrapping,
// uv_transform's order, every PNG layout (16 bit, grey, alpha, palette), JPEG, grey EXRs, the
// corners of the Radiance reader, sizes refused from every format's header, and the cache keyed
// by the file itself.
#include <gtest/gtest.h>
#include <png.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <latch>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "renderer/compare/image.h"
#include "renderer/image/jpeg_writer.h"
#include "renderer/image/png_writer.h"
#include "renderer/texture/texture.h"
#include "renderer/texture/texture_cache.h"
#include "renderer/texture/texture_file.h"
#include "renderer/util/c_file.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// The sRGB EOTF in double, to hold the float decoder to.
double srgb_eotf(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// A w x h texture whose texel (i, j) is (i, j, i + w j, 1).
Texture numbered(int w, int h) {
  std::vector<glm::vec4> texels;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) texels.emplace_back(i, j, i + w * j, 1);
  return Texture(w, h, std::move(texels));
}

// 4 x 1 with values 1, 2, 4, 8 in x (any mean of two is exact).
Texture row_of_four() {
  return Texture(4, 1, {glm::vec4(1), glm::vec4(2), glm::vec4(4), glm::vec4(8)});
}

// The message of the InputError that `load` throws ("" and a failure when it throws none).
template <typename Load>
std::string input_error_of(Load load) {
  try {
    load();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not an InputError: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

std::string load_error(const fs::path& file) {
  return input_error_of([&] { load_texture_file(file, TextureColourSpace::Srgb); });
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// --- Texture ---

TEST(TextureTexels, TheConstructorRefusesTexelsThatDoNotMatchTheSize) {
  EXPECT_THROW(Texture(0, 1, {}), std::invalid_argument);
  EXPECT_THROW(Texture(1, 0, {}), std::invalid_argument);
  EXPECT_THROW(Texture(-1, -1, {glm::vec4(1)}), std::invalid_argument);
  EXPECT_THROW(Texture(2, 2, std::vector<glm::vec4>(3)), std::invalid_argument);
  EXPECT_THROW(Texture(1, 1, std::vector<glm::vec4>(2)), std::invalid_argument);
  EXPECT_NO_THROW(Texture(1, 1, std::vector<glm::vec4>(1)));
}

TEST(TextureTexels, OddSidesHalveDownwardsAndTheBoxReadsTheClampedTexels) {
  // 5x3 -> 2x1 -> 1x1. Level 1's texel x averages columns 2x and 2x + 1, rows 0 and 1: the last
  // column and row of level 0 are not read (the rule the header states: sides halved, down to 1).
  const Texture t = numbered(5, 3);
  ASSERT_EQ(t.levels(), 3);
  EXPECT_EQ(t.level_width(1), 2);
  EXPECT_EQ(t.level_height(1), 1);
  EXPECT_EQ(t.level_width(2), 1);
  EXPECT_EQ(t.level_height(2), 1);
  EXPECT_EQ(t.texel(1, 0, 0), glm::vec4(0.5f, 0.5f, 3.0f, 1));  // (0,0) (1,0) (0,1) (1,1)
  EXPECT_EQ(t.texel(1, 1, 0), glm::vec4(2.5f, 0.5f, 5.0f, 1));  // (2,0) (3,0) (2,1) (3,1)
  // 2x1 -> 1x1: the one row read twice, so the mean of the two texels.
  EXPECT_EQ(t.texel(2, 0, 0), glm::vec4(1.5f, 0.5f, 4.0f, 1));
  EXPECT_EQ(t.memory_bytes(), (15u + 2u + 1u) * sizeof(glm::vec4));

  // 3x3 -> 1x1, which is the mean of the top-left 2x2 (values 0, 1, 3, 4), not of all nine.
  const Texture odd = numbered(3, 3);
  ASSERT_EQ(odd.levels(), 2);
  EXPECT_EQ(odd.texel(1, 0, 0), glm::vec4(0.5f, 0.5f, 2.0f, 1));

  // A column: 1x4 -> 1x2 -> 1x1.
  const Texture column = numbered(1, 4);
  ASSERT_EQ(column.levels(), 3);
  EXPECT_EQ(column.level_width(1), 1);
  EXPECT_EQ(column.level_height(1), 2);
  EXPECT_EQ(column.texel(1, 0, 1), glm::vec4(0, 2.5f, 2.5f, 1));
  EXPECT_EQ(column.texel(2, 0, 0), glm::vec4(0, 1.5f, 1.5f, 1));

  // 1x1 has one level; 4x4 three, 336 bytes.
  EXPECT_EQ(Texture(1, 1, {glm::vec4(3)}).levels(), 1);
  EXPECT_EQ(numbered(4, 4).memory_bytes(), 21u * sizeof(glm::vec4));
}

TEST(TextureSamples, BilinearWrapsBetweenTheFirstAndLastTexel) {
  const Texture t = row_of_four();
  const auto at = [&](float u, TextureWrap wrap) {
    TextureSampler s;
    s.wrap_u = wrap;
    s.wrap_v = TextureWrap::ClampToEdge;
    return t.sample({u, 0.5f}, s).x;
  };
  // u = 0 is halfway between texel -1 and texel 0; u = 1 between texel 3 and texel 4.
  EXPECT_EQ(at(0.0f, TextureWrap::Repeat), 4.5f);  // texel 3 (8) and 0 (1)
  EXPECT_EQ(at(1.0f, TextureWrap::Repeat), 4.5f);
  EXPECT_EQ(at(0.0f, TextureWrap::ClampToEdge), 1.0f);
  EXPECT_EQ(at(1.0f, TextureWrap::ClampToEdge), 8.0f);
  EXPECT_EQ(at(0.0f, TextureWrap::MirroredRepeat), 1.0f);  // texel -1 mirrors to 0
  EXPECT_EQ(at(1.0f, TextureWrap::MirroredRepeat), 8.0f);  // texel 4 mirrors to 3
  // A quarter of the way from texel 1 to texel 2.
  EXPECT_EQ(at(0.4375f, TextureWrap::Repeat), 2.5f);
}

TEST(TextureSamples, NearestWrapsFarOutsideTheTextureInBothAxes) {
  const Texture t = row_of_four();
  const auto at = [&](float u, TextureWrap wrap) {
    TextureSampler s{wrap, TextureWrap::Repeat, TextureFilter::Nearest, TextureFilter::Nearest};
    return t.sample({u, 7.3f}, s).x;
  };
  EXPECT_EQ(at(0.2499f, TextureWrap::Repeat), 1.0f);  // floor(u * 4): texel 0
  EXPECT_EQ(at(0.25f, TextureWrap::Repeat), 2.0f);    // texel 1
  EXPECT_EQ(at(0.999f, TextureWrap::Repeat), 8.0f);
  // u = -1.1 is texel -5, u = -0.6 texel -3.
  EXPECT_EQ(at(-1.1f, TextureWrap::Repeat), 8.0f);          // -5 mod 4 = 3
  EXPECT_EQ(at(-1.1f, TextureWrap::ClampToEdge), 1.0f);
  EXPECT_EQ(at(-1.1f, TextureWrap::MirroredRepeat), 8.0f);  // period 8: 3, forwards
  EXPECT_EQ(at(-0.6f, TextureWrap::MirroredRepeat), 4.0f);  // 5 in the period: mirrored to 2
  EXPECT_EQ(at(-0.6f, TextureWrap::Repeat), 2.0f);          // -3 mod 4 = 1
  // v wraps by its own mode: a column of the same values.
  const Texture column(1, 4, {glm::vec4(1), glm::vec4(2), glm::vec4(4), glm::vec4(8)});
  TextureSampler repeat_v{TextureWrap::ClampToEdge, TextureWrap::Repeat, TextureFilter::Nearest,
                          TextureFilter::Nearest};
  EXPECT_EQ(column.sample({5.0f, -0.1f}, repeat_v).x, 8.0f);
  repeat_v.wrap_v = TextureWrap::ClampToEdge;
  EXPECT_EQ(column.sample({5.0f, -0.1f}, repeat_v).x, 1.0f);
}

TEST(TextureSamples, MagnificationAndMinificationUseTheirOwnFilters) {
  const Texture t = numbered(4, 4);
  const glm::vec2 uv(0.5f, 0.125f);  // the edge between texels 1 and 2 of row 0
  const glm::vec4 nearest(2, 0, 2, 1), bilinear(1.5f, 0, 1.5f, 1);
  TextureSampler s{TextureWrap::ClampToEdge, TextureWrap::ClampToEdge, TextureFilter::Nearest, TextureFilter::Linear};
  s.mipmaps = false;
  EXPECT_EQ(t.sample(uv, s, 0.0f), nearest);          // no footprint: magnified
  EXPECT_EQ(t.sample(uv, s, 0.125f), nearest);        // lod -1: magnified
  EXPECT_EQ(t.sample(uv, s, -1.0f), nearest);         // a negative footprint reads as none
  EXPECT_EQ(t.sample(uv, s, 1.0f), bilinear);         // lod 2 without mips: level 0, minify filter
  s.magnify = TextureFilter::Linear;
  s.minify = TextureFilter::Nearest;
  EXPECT_EQ(t.sample(uv, s, 0.0f), bilinear);
  EXPECT_EQ(t.sample(uv, s, 1.0f), nearest);
}

TEST(TextureSamples, TrilinearBlendsTheTwoLevelsAroundTheLod) {
  const Texture t = numbered(4, 4);
  const glm::vec2 uv(0.375f, 0.125f);
  // Level 0 there: texel (1, 0) exactly. Level 1 (2x2; texels (0.5, 0.5, 2.5) and (2.5, 0.5, 4.5)
  // in its first row): x = 0.25, y clamped to row 0, so 0.75 * first + 0.25 * second.
  const glm::vec4 level0(1, 0, 1, 1), level1(1.0f, 0.5f, 3.0f, 1);
  ASSERT_EQ(t.texel(1, 0, 0), glm::vec4(0.5f, 0.5f, 2.5f, 1));
  const TextureSampler clamp{TextureWrap::ClampToEdge, TextureWrap::ClampToEdge};
  // lod = log2(footprint * 4).
  const auto footprint = [](float lod) { return std::exp2(lod) / 4.0f; };
  const auto near = [](glm::vec4 a, glm::vec4 b) {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(a[c], b[c], 1e-5f) << c;
  };
  near(t.sample(uv, clamp, footprint(0.25f)), 0.75f * level0 + 0.25f * level1);  // mostly the finer
  near(t.sample(uv, clamp, footprint(0.75f)), 0.25f * level0 + 0.75f * level1);
  // Past the last level's lod (2): the last level, the mean.
  EXPECT_EQ(t.sample(uv, clamp, footprint(2.5f)), glm::vec4(1.5f, 1.5f, 7.5f, 1));
  // Without mipmaps: level 0 bilinear whatever the footprint.
  TextureSampler flat = clamp;
  flat.mipmaps = false;
  EXPECT_EQ(t.sample(uv, flat, footprint(1.5f)), level0);
}

TEST(TextureSamples, NearestMinificationPicksTheRoundedLevelAndItsNearestTexel) {
  const Texture t = numbered(4, 4);
  const glm::vec2 uv(0.375f, 0.125f);
  const TextureSampler s{TextureWrap::ClampToEdge, TextureWrap::ClampToEdge, TextureFilter::Linear,
                         TextureFilter::Nearest};
  const auto footprint = [](float lod) { return std::exp2(lod) / 4.0f; };
  EXPECT_EQ(t.sample(uv, s, footprint(0.25f)), t.texel(0, 1, 0));  // round(0.25) = 0
  EXPECT_EQ(t.sample(uv, s, footprint(0.75f)), t.texel(1, 0, 0));  // level 1, texel (0, 0)
  EXPECT_EQ(t.sample(uv, s, footprint(1.25f)), t.texel(1, 0, 0));
  EXPECT_EQ(t.sample(uv, s, footprint(1.75f)), t.texel(2, 0, 0));
  EXPECT_EQ(t.sample(uv, s, footprint(9.0f)), t.texel(2, 0, 0));
}

TEST(TextureSamples, AWholeTextureFootprintReadsTheMean) {
  const Texture t(2, 2, {glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1), glm::vec4(0, 0, 1, 1), glm::vec4(1, 1, 1, 0)});
  const TextureSampler s;
  EXPECT_EQ(t.sample({0.1f, 0.9f}, s, 1.0f), glm::vec4(0.5f, 0.5f, 0.5f, 0.75f));
  EXPECT_EQ(t.sample({0.6f, 0.2f}, s, 1.0f), glm::vec4(0.5f, 0.5f, 0.5f, 0.75f));
}

TEST(TextureSamples, NonFiniteArgumentsReadInsideTheTexture) {
  const Texture t = numbered(4, 4);
  const glm::vec4 mean(1.5f, 1.5f, 7.5f, 1);
  for (const TextureFilter minify : {TextureFilter::Linear, TextureFilter::Nearest}) {
    TextureSampler s;
    s.minify = minify;
    // A footprint so large that footprint * side overflows to inf: the last level.
    EXPECT_EQ(t.sample({0.3f, 0.3f}, s, 1e38f), mean);
    EXPECT_EQ(t.sample({0.3f, 0.3f}, s, std::numeric_limits<float>::max()), mean);
  }
  // A coordinate that is not finite reads as 0 in texel space: texel (0, 0), whatever the wrap.
  for (const TextureWrap wrap : {TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat}) {
    for (const TextureFilter filter : {TextureFilter::Linear, TextureFilter::Nearest}) {
      const TextureSampler s{wrap, wrap, filter, filter};
      for (const glm::vec2 uv : {glm::vec2(kNan, kNan), glm::vec2(kInf, -kInf), glm::vec2(-kInf, kNan)}) {
        EXPECT_EQ(t.sample(uv, s), t.texel(0, 0, 0));
        EXPECT_TRUE(std::isfinite(t.sample(uv, s, kNan).x));
        EXPECT_TRUE(std::isfinite(t.sample(uv, s, kInf).x));
      }
    }
  }
}

TEST(TextureTransform, ScalesThenRotatesThenOffsetsAsKhrTextureTransformSays) {
  EXPECT_EQ(uv_transform({0, 0}, 0.0f, {1, 1}), glm::mat3(1.0f));
  const auto apply = [](const glm::mat3& m, glm::vec2 p) {
    const glm::vec3 q = m * glm::vec3(p, 1.0f);
    EXPECT_NEAR(q.z, 1.0f, 1e-6f);
    return glm::vec2(q);
  };
  const float quarter = static_cast<float>(M_PI / 2);
  // The spec's rotation [[cos, sin], [-sin, cos]] takes (0, 1) to (1, 0) at a quarter turn.
  glm::vec2 p = apply(uv_transform({0.25f, 0.5f}, quarter, {1, 1}), {0, 1});
  EXPECT_NEAR(p.x, 1.25f, 1e-6f);
  EXPECT_NEAR(p.y, 0.5f, 1e-6f);
  // (1, 1) scaled by (2, 3) is (2, 3), rotated (3, -2), offset (3.1, -1.8). Rotating before
  // scaling would give (2.1, -2.8).
  p = apply(uv_transform({0.1f, 0.2f}, quarter, {2, 3}), {1, 1});
  EXPECT_NEAR(p.x, 3.1f, 1e-5f);
  EXPECT_NEAR(p.y, -1.8f, 1e-5f);
  // A pure offset and a pure scale.
  p = apply(uv_transform({-0.5f, 2.0f}, 0.0f, {1, 1}), {0.25f, 0.75f});
  EXPECT_EQ(p, glm::vec2(-0.25f, 2.75f));
  p = apply(uv_transform({0, 0}, 0.0f, {4, 0.5f}), {0.25f, 0.5f});
  EXPECT_EQ(p, glm::vec2(1.0f, 0.25f));
}

// --- Files ---

// A PNG as libpng writes it, rows packed as the file stores them (16-bit samples big-endian).
struct RawPng {
  int width = 0, height = 0, bit_depth = 8, colour_type = PNG_COLOR_TYPE_RGB;
  std::vector<std::uint8_t> bytes;
  std::vector<png_color> palette;
  std::vector<png_byte> palette_alpha;  // tRNS
};

// Every libpng call below its setjmp, with nothing to destroy on the way out. False on an error.
bool write_raw_png_rows(std::FILE* out, const RawPng& spec, png_structp png, png_infop info, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_init_io(png, out);
  png_set_IHDR(png, info, static_cast<png_uint_32>(spec.width), static_cast<png_uint_32>(spec.height), spec.bit_depth,
               spec.colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (!spec.palette.empty()) png_set_PLTE(png, info, spec.palette.data(), static_cast<int>(spec.palette.size()));
  if (!spec.palette_alpha.empty()) {
    png_set_tRNS(png, info, spec.palette_alpha.data(), static_cast<int>(spec.palette_alpha.size()), nullptr);
  }
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

fs::path write_raw_png(const fs::path& file, RawPng spec) {
  const std::size_t row_bytes = spec.bytes.size() / static_cast<std::size_t>(spec.height);
  std::vector<png_bytep> rows;
  for (int y = 0; y < spec.height; ++y) rows.push_back(spec.bytes.data() + static_cast<std::size_t>(y) * row_bytes);
  CFile out(std::fopen(file.c_str(), "wb"));
  EXPECT_TRUE(out) << file;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  EXPECT_TRUE(write_raw_png_rows(out.get(), spec, png, info, rows.data())) << file;
  png_destroy_write_struct(&png, &info);
  return file;
}

fs::path write_rgb8_png(const fs::path& file, int width, int height, std::vector<std::uint8_t> rgb) {
  Rgb8Image image;
  image.width = width;
  image.height = height;
  image.pixels = std::move(rgb);
  CFile out(std::fopen(file.c_str(), "wb"));
  EXPECT_TRUE(out) << file;
  write_png(image, out.get(), file);
  return file;
}

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

TEST(TextureFileLayouts, SixteenBitPngKeepsItsPrecision) {
  TempDir dir;
  // Two RGB pixels: (1000, 32768, 65535) and (0, 65535, 257).
  const fs::path file = write_raw_png(dir / "deep.png", {2, 1, 16, PNG_COLOR_TYPE_RGB,
                                                          {0x03, 0xe8, 0x80, 0x00, 0xff, 0xff, 0x00, 0x00, 0xff, 0xff,
                                                           0x01, 0x01},
                                                          {},
                                                          {}});
  const auto data = load_texture_file(file, TextureColourSpace::Linear);
  ASSERT_EQ(data->width(), 2);
  EXPECT_FLOAT_EQ(data->texel(0, 0, 0).x, 1000.0f / 65535.0f);  // 8 bits would give 3 / 255
  EXPECT_FLOAT_EQ(data->texel(0, 0, 0).y, 32768.0f / 65535.0f);
  EXPECT_EQ(data->texel(0, 0, 0).z, 1.0f);
  EXPECT_EQ(data->texel(0, 0, 0).w, 1.0f);
  EXPECT_EQ(data->texel(0, 1, 0), glm::vec4(0.0f, 1.0f, 257.0f / 65535.0f, 1.0f));
  const auto colour = load_texture_file(file, TextureColourSpace::Srgb);
  EXPECT_NEAR(colour->texel(0, 0, 0).x, srgb_eotf(1000.0 / 65535.0), 1e-7);  // the linear segment
  EXPECT_NEAR(colour->texel(0, 0, 0).y, srgb_eotf(32768.0 / 65535.0), 2e-6);
  EXPECT_NEAR(colour->texel(0, 0, 0).z, 1.0, 1e-6);
  EXPECT_NEAR(colour->texel(0, 1, 0).z, srgb_eotf(257.0 / 65535.0), 1e-7);
}

TEST(TextureFileLayouts, GreyCopiesToRgbAndAlphaIsNeverSrgbDecoded) {
  TempDir dir;
  const fs::path ga = write_raw_png(dir / "ga.png", {1, 1, 8, PNG_COLOR_TYPE_GRAY_ALPHA, {128, 64}, {}, {}});
  const glm::vec4 colour = load_texture_file(ga, TextureColourSpace::Srgb)->texel(0, 0, 0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(colour[c], 0.21586f, 1e-5f) << c;
  EXPECT_FLOAT_EQ(colour.w, 64.0f / 255.0f);  // decoded it would be 0.0513
  const glm::vec4 data = load_texture_file(ga, TextureColourSpace::Linear)->texel(0, 0, 0);
  EXPECT_EQ(data, glm::vec4(128.0f / 255.0f, 128.0f / 255.0f, 128.0f / 255.0f, 64.0f / 255.0f));

  // Grey without alpha, 16 bit: alpha 1.
  const fs::path g16 =
      write_raw_png(dir / "g16.png", {2, 1, 16, PNG_COLOR_TYPE_GRAY, {0x12, 0x34, 0xff, 0xff}, {}, {}});
  const auto grey = load_texture_file(g16, TextureColourSpace::Linear);
  const float v = static_cast<float>(0x1234) / 65535.0f;
  EXPECT_EQ(grey->texel(0, 0, 0), glm::vec4(v, v, v, 1.0f));
  EXPECT_EQ(grey->texel(0, 1, 0), glm::vec4(1.0f));

  // RGBA, 8 bit.
  const fs::path rgba = write_raw_png(dir / "rgba.png", {1, 1, 8, PNG_COLOR_TYPE_RGB_ALPHA, {255, 0, 51, 0}, {}, {}});
  const glm::vec4 c = load_texture_file(rgba, TextureColourSpace::Srgb)->texel(0, 0, 0);
  EXPECT_EQ(c.x, 1.0f);
  EXPECT_EQ(c.y, 0.0f);
  EXPECT_NEAR(c.z, srgb_eotf(0.2), 1e-6);
  EXPECT_EQ(c.w, 0.0f);
}

TEST(TextureFileLayouts, APaletteWithTransparencyExpandsToRgba) {
  TempDir dir;
  // Two pixels of a 1-bit palette image, indices 0 and 1 (0b01 in the top bits of one byte).
  RawPng spec{2, 1, 1, PNG_COLOR_TYPE_PALETTE, {0x40}, {{255, 0, 0}, {0, 128, 255}}, {255, 128}};
  const auto t = load_texture_file(write_raw_png(dir / "palette.png", spec), TextureColourSpace::Srgb);
  ASSERT_EQ(t->width(), 2);
  EXPECT_EQ(t->texel(0, 0, 0), glm::vec4(1, 0, 0, 1));
  const glm::vec4 second = t->texel(0, 1, 0);
  EXPECT_EQ(second.x, 0.0f);
  EXPECT_NEAR(second.y, 0.21586f, 1e-5f);
  EXPECT_EQ(second.z, 1.0f);
  EXPECT_FLOAT_EQ(second.w, 128.0f / 255.0f);
}

TEST(TextureFileLayouts, JpegIsSrgbDecodedFromItsStoredValues) {
  TempDir dir;
  Rgb8Image image;
  image.width = image.height = 16;
  for (int i = 0; i < 256; ++i) image.pixels.insert(image.pixels.end(), {200, 100, 50});
  const fs::path file = dir / "flat.jpg";
  {
    CFile out(std::fopen(file.c_str(), "wb"));
    ASSERT_TRUE(out);
    write_jpeg(image, out.get(), file);
  }
  const auto data = load_texture_file(file, TextureColourSpace::Linear);
  const auto colour = load_texture_file(file, TextureColourSpace::Srgb);
  ASSERT_EQ(data->width(), 16);
  ASSERT_EQ(data->height(), 16);
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{7, 9}, std::pair{15, 15}}) {
    const glm::vec4 stored = data->texel(0, x, y), linear = colour->texel(0, x, y);
    // A flat colour survives JPEG to within rounding.
    EXPECT_NEAR(stored.x, 200.0f / 255.0f, 3.0f / 255.0f);
    EXPECT_NEAR(stored.y, 100.0f / 255.0f, 3.0f / 255.0f);
    EXPECT_NEAR(stored.z, 50.0f / 255.0f, 3.0f / 255.0f);
    EXPECT_EQ(stored.w, 1.0f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(linear[c], srgb_eotf(stored[c]), 2e-6) << c;
    EXPECT_EQ(linear.w, 1.0f);
  }
}

fs::path write_exr(const TempDir& dir, const std::string& name, int width, int height,
                   std::vector<std::string> channels, std::vector<float> values) {
  Image image = make_image(width, height, std::move(channels));
  image.values = std::move(values);
  write_exr_image(image, dir / name);
  return dir / name;
}

TEST(TextureFileLayouts, ExrGreyAndAlphaMapToRgba) {
  TempDir dir;
  // Grey: Y to R G B, alpha 1; values above 1 and below 0 kept, in either space.
  const fs::path y = write_exr(dir, "y.exr", 2, 1, {"Y"}, {3.5f, -0.25f});
  for (const TextureColourSpace space : {TextureColourSpace::Srgb, TextureColourSpace::Linear}) {
    const auto t = load_texture_file(y, space);
    EXPECT_EQ(t->texel(0, 0, 0), glm::vec4(3.5f, 3.5f, 3.5f, 1.0f));
    EXPECT_EQ(t->texel(0, 1, 0), glm::vec4(-0.25f, -0.25f, -0.25f, 1.0f));
  }
  const fs::path ya = write_exr(dir, "ya.exr", 1, 1, {"Y", "A"}, {0.5f, 0.25f});
  EXPECT_EQ(load_texture_file(ya, TextureColourSpace::Srgb)->texel(0, 0, 0), glm::vec4(0.5f, 0.5f, 0.5f, 0.25f));
  // RGBA, with another channel beside them that is not read.
  const fs::path rgba =
      write_exr(dir, "rgba.exr", 1, 2, {"R", "G", "B", "A", "Z"},
                {0.1f, 0.2f, 0.3f, 0.4f, 9.0f, 5.0f, 6.0f, 7.0f, 0.0f, 9.0f});
  const auto t = load_texture_file(rgba, TextureColourSpace::Srgb);
  EXPECT_EQ(t->texel(0, 0, 0), glm::vec4(0.1f, 0.2f, 0.3f, 0.4f));
  EXPECT_EQ(t->texel(0, 0, 1), glm::vec4(5.0f, 6.0f, 7.0f, 0.0f));
  // No colour at all: refused, naming the file.
  const fs::path depth = write_exr(dir, "depth.exr", 1, 1, {"Z"}, {1.0f});
  EXPECT_TRUE(contains(load_error(depth), "depth.exr"));
}

// --- Radiance HDR ---

fs::path write_hdr(const TempDir& dir, const std::string& name, const std::string& resolution, const std::string& body,
                   const std::string& header = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n") {
  const fs::path file = dir / name;
  write_bytes(file, header + "\n" + resolution + "\n" + body);
  return file;
}

std::string bytes(std::initializer_list<int> values) {
  std::string s;
  for (int v : values) s += static_cast<char>(v);
  return s;
}

TEST(TextureRadiance, RunLengthScanlinesMixRunsAndLiteralsInEveryChannel) {
  TempDir dir;
  // 9 x 2, exponent 136 (scale 1) or 137 (scale 2), so each float is its mantissa (times 2).
  std::string body = bytes({2, 2, 0, 9});
  body += bytes({0x84, 10, 0x03, 20, 30, 40, 0x82, 50});  // R: 10 x4, 20 30 40, 50 x2
  body += bytes({0x09, 0, 1, 2, 3, 4, 5, 6, 7, 8});        // G: 0..8
  body += bytes({0x89, 0});                                // B: 0 x9
  body += bytes({0x89, 136});                              // E
  body += bytes({2, 2, 0, 9});
  body += bytes({0x09, 1, 2, 3, 4, 5, 6, 7, 8, 9});  // R: 1..9
  body += bytes({0x89, 7});                          // G: 7 x9
  body += bytes({0x85, 3, 0x04, 4, 5, 6, 7});        // B: 3 x5, 4 5 6 7
  body += bytes({0x84, 137, 0x85, 0});               // E: 137 x4, then 0 (black) x5
  const fs::path file = write_hdr(dir, "mixed.hdr", "-Y 2 +X 9", body,
                                  "#?RGBE\n# made by hand\nEXPOSURE=1.0\nFORMAT=32-bit_rle_rgbe\n");
  const auto t = load_texture_file(file, TextureColourSpace::Srgb);
  ASSERT_EQ(t->width(), 9);
  ASSERT_EQ(t->height(), 2);
  const float row0_r[9] = {10, 10, 10, 10, 20, 30, 40, 50, 50};
  for (int x = 0; x < 9; ++x) {
    EXPECT_EQ(t->texel(0, x, 0), glm::vec4(row0_r[x], static_cast<float>(x), 0.0f, 1.0f)) << x;
  }
  for (int x = 0; x < 4; ++x) EXPECT_EQ(t->texel(0, x, 1), glm::vec4(2.0f * (x + 1), 14.0f, 6.0f, 1.0f)) << x;
  for (int x = 4; x < 9; ++x) EXPECT_EQ(t->texel(0, x, 1), glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)) << x;
}

TEST(TextureRadiance, FlatScanlinesOfAWideImageAreReadAsPixels) {
  TempDir dir;
  // Width 8 could be run-length, but the first pixel does not start 2 2: flat, 4 bytes a pixel.
  std::string body;
  for (int k = 0; k < 8; ++k) body += bytes({k, 2 * k, 3 * k, 135});  // scale 1/2
  const auto t = load_texture_file(write_hdr(dir, "flat.hdr", "-Y 1 +X 8", body), TextureColourSpace::Linear);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(t->texel(0, k, 0), glm::vec4(0.5f * k, 1.0f * k, 1.5f * k, 1.0f)) << k;
}

TEST(TextureRadiance, MalformedFilesAreInputErrorsNamingTheFile) {
  TempDir dir;
  const std::string good_row = bytes({2, 2, 0, 9, 0x89, 1, 0x89, 2, 0x89, 3, 0x89, 136});
  struct Case {
    std::string name, resolution, body, header, says;
  };
  const std::string standard = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n";
  const std::vector<Case> cases = {
      {"cut_rle.hdr", "-Y 2 +X 9", good_row + good_row.substr(0, 7), standard, ""},
      {"cut_flat.hdr", "-Y 1 +X 3", bytes({1, 1, 1, 136, 1, 1}), standard, ""},
      {"long_run.hdr", "-Y 1 +X 9", bytes({2, 2, 0, 9, 0x8a, 1}), standard, ""},
      {"long_literal.hdr", "-Y 1 +X 9", bytes({2, 2, 0, 9, 0x0a, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}), standard, ""},
      {"empty_literal.hdr", "-Y 1 +X 9", bytes({2, 2, 0, 9, 0x00, 1}), standard, ""},
      {"wrong_length.hdr", "-Y 1 +X 9", bytes({2, 2, 0, 8}) + good_row.substr(4), standard, ""},
      {"flipped.hdr", "+Y 1 +X 1", bytes({1, 1, 1, 136}), standard, "+Y 1 +X 1"},
      {"no_resolution.hdr", "", "", standard, ""},
      {"xyze.hdr", "-Y 1 +X 1", bytes({1, 1, 1, 136}), "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n", "32-bit_rle_rgbe"},
  };
  for (const Case& c : cases) {
    const fs::path file = write_hdr(dir, c.name, c.resolution, c.body, c.header);
    const std::string what = load_error(file);
    EXPECT_TRUE(contains(what, c.name)) << c.name << ": " << what;
    EXPECT_TRUE(contains(what, c.says)) << c.name << ": " << what;
  }
  // A header that never ends.
  write_bytes(dir / "endless.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n");
  EXPECT_TRUE(contains(load_error(dir / "endless.hdr"), "endless.hdr"));
  // Neither a texture nor there.
  EXPECT_TRUE(contains(load_error(dir.write("notes.png", "just some text")), "notes.png"));
  EXPECT_TRUE(contains(load_error(dir / "missing.png"), "missing.png"));
}

// --- Sizes from headers ---

// The message for `file` must name it and its size, and say nothing was decoded.
void expect_refused_from_header(const fs::path& file, const std::string& size) {
  const std::string what = load_error(file);
  EXPECT_TRUE(contains(what, file.filename().string())) << what;
  EXPECT_TRUE(contains(what, size)) << what;
  EXPECT_TRUE(contains(what, "not decoded")) << what;
}

TEST(TextureLimits, EveryFormatIsRefusedFromItsHeaderJustPastTheLimits) {
  TempDir dir;
  // Radiance: no pixels follow, so a reader that decoded first would fail otherwise.
  expect_refused_from_header(write_hdr(dir, "wide.hdr", "-Y 1 +X 16385", ""), "16385x1");
  expect_refused_from_header(write_hdr(dir, "many.hdr", "-Y 8193 +X 8192", ""), "8192x8193");
  expect_refused_from_header(write_hdr(dir, "huge.hdr", "-Y 20000 +X 20000", ""), "20000x20000");

  // PNG: a real 1x1 file whose IHDR is rewritten (its CRC then fails, which a decoder would say).
  const auto png_claiming = [&](const std::string& name, std::uint32_t width, std::uint32_t height) {
    std::string png = read_bytes(write_rgb8_png(dir / name, 1, 1, {1, 2, 3}));
    for (int k = 0; k < 4; ++k) {
      png[16 + static_cast<std::size_t>(k)] = static_cast<char>((width >> (24 - 8 * k)) & 0xff);
      png[20 + static_cast<std::size_t>(k)] = static_cast<char>((height >> (24 - 8 * k)) & 0xff);
    }
    write_bytes(dir / name, png);
    return dir / name;
  };
  expect_refused_from_header(png_claiming("tall.png", 1, 16385), "1x16385");
  expect_refused_from_header(png_claiming("many.png", 8193, 8192), "8193x8192");

  // JPEG: a real one whose start-of-frame says 8193 x 8192.
  Rgb8Image image;
  image.width = image.height = 8;
  image.pixels.assign(8 * 8 * 3, 90);
  const fs::path jpeg = dir / "many.jpg";
  {
    CFile out(std::fopen(jpeg.c_str(), "wb"));
    ASSERT_TRUE(out);
    write_jpeg(image, out.get(), jpeg);
  }
  std::string jpg = read_bytes(jpeg);
  const std::size_t sof = jpg.find("\xff\xc0");
  ASSERT_NE(sof, std::string::npos);
  // FF C0, length (2), precision (1), height (2), width (2).
  jpg[sof + 5] = static_cast<char>(8192 >> 8);
  jpg[sof + 6] = static_cast<char>(8192 & 0xff);
  jpg[sof + 7] = static_cast<char>(8193 >> 8);
  jpg[sof + 8] = static_cast<char>(8193 & 0xff);
  write_bytes(jpeg, jpg);
  expect_refused_from_header(jpeg, "8193x8192");

  // EXR: a real 1x1 whose dataWindow attribute says (0, 0) - (8192, 8191).
  const fs::path exr = write_exr(dir, "many.exr", 1, 1, {"R", "G", "B"}, {1, 2, 3});
  std::string e = read_bytes(exr);
  const std::string attribute("dataWindow\0box2i\0", 17);
  const std::size_t at = e.find(attribute);
  ASSERT_NE(at, std::string::npos);
  const std::size_t box = at + attribute.size() + 4;  // past the attribute's size
  const auto put = [&](std::size_t offset, std::int32_t v) {
    for (int k = 0; k < 4; ++k) e[offset + static_cast<std::size_t>(k)] = static_cast<char>((v >> (8 * k)) & 0xff);
  };
  put(box + 8, 8192);
  put(box + 12, 8191);
  write_bytes(exr, e);
  expect_refused_from_header(exr, "8193x8192");
}

// --- Cache ---

TEST(TextureCacheSharing, ThreadsAskingAtOnceShareOneDecode) {
  TempDir dir;
  const fs::path file = write_rgb8_png(dir / "big.png", 256, 256, std::vector<std::uint8_t>(256 * 256 * 3, 77));
  TextureCache cache;
  constexpr int kThreads = 8;
  std::latch start(kThreads);
  std::vector<std::shared_ptr<const Texture>> got(kThreads);
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] {
      start.arrive_and_wait();
      got[static_cast<std::size_t>(i)] = cache.get(file, TextureColourSpace::Srgb);
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(cache.decodes(), 1u);
  for (const auto& g : got) EXPECT_EQ(g, got[0]);
  ASSERT_NE(got[0], nullptr);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(cache.get(file, TextureColourSpace::Srgb), got[0]);
  EXPECT_EQ(cache.decodes(), 1u);
}

TEST(TextureCacheSharing, OneFileNamedTwoWaysIsOneTexture) {
  TempDir dir;
  const fs::path file = write_rgb8_png(dir / "t.png", 1, 1, {1, 2, 3});
  fs::create_directories(dir / "sub");
  TextureCache cache;
  const auto a = cache.get(file, TextureColourSpace::Linear);
  EXPECT_EQ(cache.get(dir / "." / "t.png", TextureColourSpace::Linear), a);
  EXPECT_EQ(cache.get(dir / "sub" / ".." / "t.png", TextureColourSpace::Linear), a);
  EXPECT_EQ(cache.decodes(), 1u);
  // Another space is another texture, and both stay.
  const auto b = cache.get(file, TextureColourSpace::Srgb);
  EXPECT_NE(a, b);
  EXPECT_EQ(cache.get(file, TextureColourSpace::Linear), a);
  EXPECT_EQ(cache.get(file, TextureColourSpace::Srgb), b);
  EXPECT_EQ(cache.decodes(), 2u);
}

TEST(TextureCacheSharing, ANewModificationTimeOrSizeIsANewDecode) {
  TempDir dir;
  const fs::path file = write_rgb8_png(dir / "t.png", 1, 1, {10, 20, 30});
  TextureCache cache;
  const auto first = cache.get(file, TextureColourSpace::Linear);
  // The same bytes with a later time: decoded again; the first texture stays as it was.
  fs::last_write_time(file, fs::last_write_time(file) + std::chrono::seconds(5));
  const auto touched = cache.get(file, TextureColourSpace::Linear);
  EXPECT_NE(touched, first);
  EXPECT_EQ(cache.decodes(), 2u);
  EXPECT_EQ(cache.get(file, TextureColourSpace::Linear), touched);
  // Another size (2x1) at the same time as before: decoded again.
  const auto time = fs::last_write_time(file);
  write_rgb8_png(file, 2, 1, {200, 20, 30, 40, 50, 60});
  fs::last_write_time(file, time);
  const auto resized = cache.get(file, TextureColourSpace::Linear);
  EXPECT_EQ(resized->width(), 2);
  EXPECT_FLOAT_EQ(resized->texel(0, 0, 0).x, 200.0f / 255.0f);
  EXPECT_EQ(cache.decodes(), 3u);
  EXPECT_FLOAT_EQ(first->texel(0, 0, 0).x, 10.0f / 255.0f);
}

TEST(TextureCacheSharing, ReleasedTexturesAreDecodedAgain) {
  TempDir dir;
  const fs::path file = write_rgb8_png(dir / "t.png", 1, 1, {10, 20, 30});
  TextureCache cache;
  std::weak_ptr<const Texture> weak;
  {
    const auto held = cache.get(file, TextureColourSpace::Srgb);
    const auto again = cache.get(file, TextureColourSpace::Srgb);
    EXPECT_EQ(held, again);
    weak = held;
  }
  EXPECT_TRUE(weak.expired());  // the cache holds nothing itself
  EXPECT_EQ(cache.decodes(), 1u);
  const auto later = cache.get(file, TextureColourSpace::Srgb);
  EXPECT_EQ(cache.decodes(), 2u);
  EXPECT_EQ(cache.get(file, TextureColourSpace::Srgb), later);
  EXPECT_EQ(cache.decodes(), 2u);
}

TEST(TextureCacheSharing, AFailedDecodeReachesEveryAskerAndIsTriedAgain) {
  TempDir dir;
  // A PNG signature and IHDR for 4x4, then garbage: refused by the decoder, not the size check.
  std::string png = read_bytes(write_rgb8_png(dir / "broken.png", 4, 4, std::vector<std::uint8_t>(48, 9)));
  png.resize(33);
  png += std::string(40, '\x55');
  write_bytes(dir / "broken.png", png);
  TextureCache cache;
  constexpr int kThreads = 8;
  std::latch start(kThreads);
  std::vector<std::string> errors(kThreads);
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] {
      start.arrive_and_wait();
      try {
        cache.get(dir / "broken.png", TextureColourSpace::Srgb);
        errors[static_cast<std::size_t>(i)] = "no error";
      } catch (const InputError& e) {
        errors[static_cast<std::size_t>(i)] = e.what();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (const std::string& e : errors) EXPECT_TRUE(contains(e, "broken.png")) << e;
  const std::uint64_t attempts = cache.decodes();
  EXPECT_GE(attempts, 1u);
  EXPECT_LE(attempts, static_cast<std::uint64_t>(kThreads));
  // Nothing is kept for a failure: each later call tries again, and a repaired file is read.
  EXPECT_THROW(cache.get(dir / "broken.png", TextureColourSpace::Srgb), InputError);
  EXPECT_EQ(cache.decodes(), attempts + 1);
  write_rgb8_png(dir / "broken.png", 1, 1, {255, 255, 255});
  EXPECT_EQ(cache.get(dir / "broken.png", TextureColourSpace::Srgb)->texel(0, 0, 0), glm::vec4(1.0f));
  EXPECT_EQ(cache.decodes(), attempts + 2);
}

TEST(TextureCacheSharing, TheProcessHasOneCache) { EXPECT_EQ(&TextureCache::process(), &TextureCache::process()); }

}  // namespace
}  // namespace farm
