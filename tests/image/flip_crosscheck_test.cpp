// renderer/compare/flip against NVIDIA's own FLIP (flip-evaluator, the Python package of the
// authors' C++ code): varied image pairs are built here, written as the files users compare (8-bit
// PNG for LDR, float EXR for HDR), read by flip-evaluator, and handed to flip_ldr / flip_hdr as
// the very same pixel values. The means must agree to 0.002.
#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "renderer/compare/flip.h"
#include "renderer/image/png_writer.h"
#include "renderer/util/thread_pool.h"
#include "tests/support/run_command.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr double kTolerance = 0.002;

// Deterministic noise in [0, 1) from a position and a seed (std:: distributions differ between
// standard libraries; these pairs should not).
float noise(std::uint32_t x, std::uint32_t y, std::uint32_t seed) {
  std::uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return static_cast<float>(h >> 8) / 16777216.0f;
}

struct Rgb {
  float r, g, b;
};

Image make_rgb(int w, int h, const std::function<Rgb(int, int)>& pixel) {
  Image image;
  image.width = w;
  image.height = h;
  image.channels = {"R", "G", "B"};
  image.values.resize(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Rgb c = pixel(x, y);
      image.at(x, y, 0) = c.r;
      image.at(x, y, 1) = c.g;
      image.at(x, y, 2) = c.b;
    }
  }
  return image;
}

Image map_pixels(const Image& in, const std::function<Rgb(int, int, Rgb)>& f) {
  return make_rgb(in.width, in.height,
                  [&](int x, int y) { return f(x, y, {in.at(x, y, 0), in.at(x, y, 1), in.at(x, y, 2)}); });
}

Rgb sample(const Image& in, int x, int y) {
  x = std::clamp(x, 0, in.width - 1);
  y = std::clamp(y, 0, in.height - 1);
  return {in.at(x, y, 0), in.at(x, y, 1), in.at(x, y, 2)};
}

Image box_blur(const Image& in) {
  return make_rgb(in.width, in.height, [&](int x, int y) {
    Rgb sum{0, 0, 0};
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Rgb c = sample(in, x + dx, y + dy);
        sum = {sum.r + c.r / 9, sum.g + c.g / 9, sum.b + c.b / 9};
      }
    }
    return sum;
  });
}

float srgb_encode(float linear) {
  linear = std::clamp(linear, 0.0f, 1.0f);
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

// What an 8-bit PNG holds of a display value, as a reader gives it back: k / 255.
float quantise(float v) { return std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f; }

Image quantised(const Image& in) {
  return map_pixels(in, [](int, int, Rgb c) { return Rgb{quantise(c.r), quantise(c.g), quantise(c.b)}; });
}

// A small linear-light "render": a lit sphere above a checker floor under a sky, with the sun
// (HDR) as a hot disc. `sun` is the sun disc's radiance; LDR pairs use a dim one.
Image render(int w, int h, float sun) {
  return make_rgb(w, h, [&](int px, int py) {
    const float u = (px + 0.5f) / w * 2.0f - 1.0f, v = 1.0f - (py + 0.5f) / h * 2.0f;
    const float aspect = static_cast<float>(w) / h;
    const float sx = u * aspect, sy = v;
    // Sphere at the centre, radius 0.45.
    const float cx = sx - 0.1f, cy = sy + 0.05f, r2 = cx * cx + cy * cy;
    if (r2 < 0.45f * 0.45f) {
      const float nz = std::sqrt(0.45f * 0.45f - r2) / 0.45f, nx = cx / 0.45f, ny = cy / 0.45f;
      const float lambert = std::max(0.0f, 0.5f * nx + 0.6f * ny + 0.62f * nz);
      const float spec = std::pow(std::max(0.0f, 0.3f * nx + 0.5f * ny + 0.81f * nz), 40.0f);
      return Rgb{0.7f * lambert + 0.02f + 4.0f * spec * sun / 50.0f, 0.25f * lambert + 0.02f + spec, 0.1f * lambert + 0.03f + spec};
    }
    if (sy < -0.35f) {  // the floor: a checker in perspective, darker under the sphere
      const float depth = 0.35f / (-sy);
      const int check = (static_cast<int>(std::floor(sx * depth * 4.0f)) + static_cast<int>(std::floor(depth * 6.0f))) & 1;
      const float shadow = std::clamp(std::hypot(sx - 0.2f, (sy + 0.55f) * 2.5f) * 2.0f, 0.25f, 1.0f);
      const float albedo = check ? 0.8f : 0.15f;
      return Rgb{albedo * shadow, albedo * shadow * 0.95f, albedo * shadow * 0.9f};
    }
    const float sun_distance = std::hypot(sx + 0.9f, sy - 0.7f);
    if (sun_distance < 0.08f) return Rgb{sun, sun * 0.9f, sun * 0.7f};
    const float t = (sy + 0.35f) / 1.35f;  // the sky: pale at the horizon, blue above
    return Rgb{0.9f - 0.6f * t, 0.95f - 0.45f * t, 1.0f - 0.1f * t};
  });
}

Image display(const Image& linear) {
  return quantised(
      map_pixels(linear, [](int, int, Rgb c) { return Rgb{srgb_encode(c.r), srgb_encode(c.g), srgb_encode(c.b)}; }));
}

struct Pair {
  std::string name;
  bool hdr;
  Image reference, test;
};

std::vector<Pair> ldr_pairs() {
  std::vector<Pair> pairs;
  const Image scene = display(render(192, 128, 1.0f));
  pairs.push_back({"ldr noise", false, scene, quantised(map_pixels(scene, [](int x, int y, Rgb c) {
                     const float n = 0.12f * (noise(x, y, 1) - 0.5f);
                     return Rgb{c.r + n, c.g + 0.12f * (noise(x, y, 2) - 0.5f), c.b + n};
                   }))});
  pairs.push_back({"ldr shift", false, scene, quantised(map_pixels(scene, [&](int x, int y, Rgb) {
                     return sample(scene, x - 1, y);  // one pixel to the right
                   }))});
  pairs.push_back({"ldr blur", false, scene, quantised(box_blur(scene))});
  pairs.push_back({"ldr colour gain", false, scene, quantised(map_pixels(scene, [](int, int, Rgb c) {
                     return Rgb{c.r * 1.15f, c.g, c.b * 0.85f};
                   }))});
  pairs.push_back({"ldr hot pixels", false, scene, quantised(map_pixels(scene, [](int x, int y, Rgb c) {
                     return noise(x, y, 3) < 0.01f ? Rgb{1.0f, 1.0f, noise(x, y, 4)} : c;
                   }))});
  // A smooth ramp against the same ramp in eight bands.
  const Image ramp = quantised(make_rgb(256, 96, [](int x, int y) {
    const float t = x / 255.0f;
    return Rgb{t, 0.3f + 0.4f * t * (y / 95.0f), 1.0f - t};
  }));
  pairs.push_back({"ldr gradient vs banded", false, ramp, quantised(map_pixels(ramp, [](int, int, Rgb c) {
                     const auto band = [](float v) { return std::floor(v * 8.0f) / 8.0f + 1.0f / 16.0f; };
                     return Rgb{band(c.r), band(c.g), band(c.b)};
                   }))});
  // A larger render against a noisy one (few samples per pixel: noise grows with brightness).
  const Image linear = render(256, 256, 1.0f);
  const Image noisy = map_pixels(linear, [](int x, int y, Rgb c) {
    const float n = 1.0f + 0.8f * (noise(x, y, 5) - 0.5f);
    return Rgb{c.r * n, c.g * n, c.b * (1.0f + 0.8f * (noise(x, y, 6) - 0.5f))};
  });
  pairs.push_back({"ldr render vs noisy render", false, display(linear), display(noisy)});
  // Grey images (one channel Y, read as R = G = B): stripes of text-like strokes, and the same
  // with every other stroke a grey level lighter.
  const auto grey = [](int w, int h, const std::function<float(int, int)>& value) {
    Image image;
    image.width = w;
    image.height = h;
    image.channels = {"Y"};
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) image.values.push_back(quantise(value(x, y)));
    return image;
  };
  const auto stroke = [](int x, int y) { return (x / 3 + y / 7) % 4 == 0 && y % 7 < 5; };
  pairs.push_back({"ldr grey strokes", false, grey(128, 128, [&](int x, int y) { return stroke(x, y) ? 0.1f : 0.9f; }),
                   grey(128, 128, [&](int x, int y) { return stroke(x, y) ? ((x / 12) % 2 ? 0.3f : 0.1f) : 0.9f; })});
  return pairs;
}

std::vector<Pair> hdr_pairs() {
  std::vector<Pair> pairs;
  const Image scene = render(128, 96, 60.0f);
  pairs.push_back({"hdr noise", true, scene, map_pixels(scene, [](int x, int y, Rgb c) {
                     const float n = 1.0f + 0.4f * (noise(x, y, 7) - 0.5f);
                     return Rgb{c.r * n, c.g * n, c.b * n};
                   })});
  pairs.push_back({"hdr fireflies", true, scene, map_pixels(scene, [](int x, int y, Rgb c) {
                     return noise(x, y, 8) < 0.003f ? Rgb{400.0f, 350.0f, 300.0f} : c;
                   })});
  pairs.push_back({"hdr exposure gain", true, scene, map_pixels(scene, [](int, int, Rgb c) {
                     return Rgb{c.r * 1.3f, c.g * 1.3f, c.b * 1.3f};
                   })});
  pairs.push_back({"hdr blur", true, scene, box_blur(scene)});
  // A wide dynamic range (many exposures) at another size.
  const Image bright = render(192, 112, 2000.0f);
  pairs.push_back({"hdr wide range shift", true, bright, map_pixels(bright, [&](int x, int y, Rgb) {
                     return sample(bright, x, y - 1);
                   })});
  // An object on a black background: the median luminance is 0 (held to FLT_EPSILON), which
  // makes for a wide range of exposures.
  const Image object = make_rgb(96, 64, [](int x, int y) {
    const float d = std::hypot(x - 48.0f, y - 32.0f);
    return d < 20.0f ? Rgb{2.0f - d / 20.0f, 0.8f, 0.3f + d / 40.0f} : Rgb{0.0f, 0.0f, 0.0f};
  });
  pairs.push_back({"hdr object on black", true, object, map_pixels(object, [](int x, int y, Rgb c) {
                     const float n = 1.0f + 0.5f * (noise(x, y, 9) - 0.5f);
                     return Rgb{c.r * n, c.g * n, c.b * n};
                   })});
  return pairs;
}

void write_png_file(const Image& image, const fs::path& file) {
  Rgb8Image out;
  out.width = image.width;
  out.height = image.height;
  const std::size_t channels = image.channels.size();  // 3, or 1 for grey
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    for (std::size_t c = 0; c < 3; ++c) {
      const float v = image.values[p * channels + (channels == 1 ? 0 : c)];
      out.pixels.push_back(static_cast<std::uint8_t>(std::lround(v * 255.0f)));
    }
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "wb"), &std::fclose);
  ASSERT_TRUE(f) << file;
  write_png(out, f.get(), file);
}

void write_exr_file(const Image& image, const fs::path& file) {
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::NO_COMPRESSION;
  Imf::FrameBuffer frame;
  const std::size_t pixel = 3 * sizeof(float), row = pixel * static_cast<std::size_t>(image.width);
  const char* names[] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
    frame.insert(names[c], Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(image.values.data() + c)),
                                      pixel, row));
  }
  Imf::OutputFile out(file.c_str(), header);
  out.setFrameBuffer(frame);
  out.writePixels(image.height);
}

TEST(FlipCrossCheck, MeansAgreeWithFlipEvaluator) {
  const std::string python = FARM_TEST_PYTHON;
  ASSERT_TRUE(fs::exists(python)) << "no Python test tools at " << python
                                  << ": run deploy/install-deps.sh (it makes build/test-venv with flip-evaluator)";
  test::TempDir dir;
  std::vector<Pair> pairs = ldr_pairs();
  for (Pair& p : hdr_pairs()) pairs.push_back(std::move(p));

  std::string command = test::shell_quote(python) + " " +
                        test::shell_quote(std::string(FARM_SOURCE_DIR) + "/tests/python/flip_means.py");
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const std::string ext = pairs[i].hdr ? ".exr" : ".png";
    const fs::path ref = dir / ("ref" + std::to_string(i) + ext), test = dir / ("test" + std::to_string(i) + ext);
    if (pairs[i].hdr) {
      write_exr_file(pairs[i].reference, ref);
      write_exr_file(pairs[i].test, test);
    } else {
      write_png_file(pairs[i].reference, ref);
      write_png_file(pairs[i].test, test);
    }
    command += std::string(pairs[i].hdr ? " HDR " : " LDR ") + test::shell_quote(ref) + " " + test::shell_quote(test);
  }
  const test::CommandResult run = test::run_command(command);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // The JSON is the last line; anything flip-evaluator says goes before it.
  const std::size_t start = run.output.rfind("\n[", run.output.size() - 2);
  const nlohmann::json theirs = nlohmann::json::parse(run.output.substr(start == std::string::npos ? 0 : start + 1));
  ASSERT_EQ(theirs.size(), pairs.size()) << run.output;

  ThreadPool pool(2);
  std::printf("%-28s %10s %15s %11s  %s\n", "pair", "ours", "flip-evaluator", "difference", "exposures (HDR)");
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const Pair& p = pairs[i];
    const FlipResult ours = p.hdr ? flip_hdr(p.reference, p.test, FlipOptions{}, &pool)
                                  : flip_ldr(p.reference, p.test, FlipOptions{}, &pool);
    const double expected = theirs[i]["mean"].get<double>();
    std::printf("%-28s %10.6f %15.6f %11.2e", p.name.c_str(), ours.mean, expected, ours.mean - expected);
    if (p.hdr) std::printf("  %d in [%.3f, %.3f]", ours.exposure_count, ours.start_exposure, ours.stop_exposure);
    std::printf("\n");
    EXPECT_NEAR(ours.mean, expected, kTolerance) << p.name;
    EXPECT_GT(ours.mean, 0.0) << p.name;
    if (p.hdr) {
      EXPECT_NEAR(ours.start_exposure, theirs[i]["start_exposure"].get<double>(), 1e-4) << p.name;
      EXPECT_NEAR(ours.stop_exposure, theirs[i]["stop_exposure"].get<double>(), 1e-4) << p.name;
      EXPECT_EQ(ours.exposure_count, theirs[i]["exposure_count"].get<int>()) << p.name;
    }
  }
}

}  // namespace
}  // namespace farm
