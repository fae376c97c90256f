#include "renderer/compare/flip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "renderer/compare/flip_colour.h"
#include "renderer/compare/flip_pipeline.h"
#include "renderer/util/thread_pool.h"

namespace farm {
namespace {

using flip_detail::clamp01;

// Where an image's colour lies: R G B, or one grey channel Y read three times.
struct ColourView {
  const float* values;
  std::size_t stride;  // floats per pixel
  std::array<std::size_t, 3> offsets;
  int width;

  float at(int x, int y, int c) const {
    const std::size_t pixel = static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x);
    return values[pixel * stride + offsets[static_cast<std::size_t>(c)]];
  }
};

// The channel lookup of colour_channels(), kept here so FLIP needs nothing but the Image struct.
std::optional<std::size_t> find_channel(const Image& image, const char* name) {
  const auto it = std::find(image.channels.begin(), image.channels.end(), name);
  if (it == image.channels.end()) return std::nullopt;
  return static_cast<std::size_t>(it - image.channels.begin());
}

ColourView colour_view(const Image& image, const char* role) {
  const std::size_t stride = image.channels.size();
  if (image.values.size() != image.pixel_count() * stride)
    throw std::invalid_argument(std::string("FLIP: the ") + role + " image holds " +
                                std::to_string(image.values.size()) + " values, not width x height x channels");
  const auto r = find_channel(image, "R"), g = find_channel(image, "G"), b = find_channel(image, "B");
  if (r && g && b) return {image.values.data(), stride, {*r, *g, *b}, image.width};
  if (const auto y = find_channel(image, "Y")) return {image.values.data(), stride, {*y, *y, *y}, image.width};
  std::string names;
  for (const std::string& c : image.channels) names += (names.empty() ? "" : " ") + c;
  throw std::invalid_argument(std::string("FLIP: the ") + role +
                              " image has no colour channels (needs R G B, or Y for grey); it has: " +
                              (names.empty() ? "none" : names));
}

void check_pair(const Image& reference, const Image& test, const FlipOptions& options) {
  if (reference.width != test.width || reference.height != test.height)
    throw std::invalid_argument("FLIP: the images differ in size: reference " + std::to_string(reference.width) +
                                "x" + std::to_string(reference.height) + ", test " + std::to_string(test.width) +
                                "x" + std::to_string(test.height));
  if (reference.width <= 0 || reference.height <= 0) throw std::invalid_argument("FLIP: the images are empty");
  if (!(options.pixels_per_degree > 0.0) || !std::isfinite(options.pixels_per_degree))
    throw std::invalid_argument("FLIP: pixels per degree must be positive");
}

// sRGB decoding. 8-bit images hold k/255 exactly, so a table of those 256 values answers most
// pixels without a pow.
class SrgbDecoder {
 public:
  SrgbDecoder() {
    for (int k = 0; k < 256; ++k) table_[static_cast<std::size_t>(k)] = decode(static_cast<float>(k) / 255.0f);
  }
  float operator()(float encoded) const {
    if (encoded >= 0.0f && encoded <= 1.0f) {
      const auto k = static_cast<std::size_t>(encoded * 255.0f + 0.5f);
      if (static_cast<float>(k) / 255.0f == encoded) return table_[k];
    }
    return decode(encoded);
  }

 private:
  static float decode(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
  }
  std::array<float, 256> table_{};
};

// The ACES filmic curve as fitted by Narkowicz (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14),
// applied to 0.6 x: the fit includes an exposure of 0.6 that HDR-FLIP's exposures replace.
// Written as a ratio of quadratics n2 x^2 + n1 x (+ 0) over d2 x^2 + d1 x + d0.
constexpr float kAcesPre = 0.6f;
constexpr float kN2 = kAcesPre * kAcesPre * 2.51f, kN1 = kAcesPre * 0.03f;
constexpr float kD2 = kAcesPre * kAcesPre * 2.43f, kD1 = kAcesPre * 0.59f, kD0 = 0.14f;

inline float aces(float x) { return (x * x * kN2 + x * kN1) / (x * x * kD2 + x * kD1 + kD0); }

// The automatic exposure range of HDR-FLIP (Andersson et al. 2021): the darkest
// exposure maps the reference's brightest luminance to 0.85 after tone mapping, the brightest
// exposure does so for its median luminance. Computed in float, as flip-evaluator does, so that
// the number of exposures (a ceiling) agrees with it.
void automatic_exposures(const Image& reference, const ColourView& view, float& start, float& stop) {
  std::vector<float> luminance;
  luminance.reserve(reference.pixel_count());
  float largest = 0.0f;
  for (int y = 0; y < reference.height; ++y) {
    for (int x = 0; x < reference.width; ++x) {
      const float l = 0.2126f * view.at(x, y, 0) + 0.7152f * view.at(x, y, 1) + 0.0722f * view.at(x, y, 2);
      if (!std::isfinite(l)) continue;  // an Inf would make the range infinite
      luminance.push_back(l);
      largest = std::max(largest, l);
    }
  }
  // x_max: where the tone curve reaches 0.85, the larger root of n(x) - 0.85 d(x) = 0.
  constexpr float target = 0.85f;
  const float a = kN2 - target * kD2, b = kN1 - target * kD1, c = -target * kD0;
  const float half = -0.5f * (b / a);
  const float x_max = half + std::sqrt(half * half - c / a);

  // The upper median, as the tool takes it, held (as flip-evaluator 1.7 does) to at least
  // FLT_EPSILON: a reference that is mostly black, a render on an empty background, would have
  // no stop exposure otherwise. The brightest luminance is held there too, so that an all-black
  // reference gets a range (flip-evaluator stops with an error on one).
  constexpr float smallest = std::numeric_limits<float>::epsilon();
  auto middle = luminance.begin() + static_cast<std::ptrdiff_t>(luminance.size() / 2);
  std::nth_element(luminance.begin(), middle, luminance.end());
  const float median = std::max(luminance.empty() ? 0.0f : *middle, smallest);
  largest = std::max(largest, smallest);
  start = std::log2(x_max / largest);
  stop = std::log2(x_max / median);
}

// The pool to run on: the caller's, else one of every hardware thread for this call.
class PoolChoice {
 public:
  explicit PoolChoice(ThreadPool* given) : pool_(given) {
    if (!pool_) pool_ = &own_.emplace(resolve_thread_count(0));
  }
  ThreadPool& operator*() const { return *pool_; }

 private:
  std::optional<ThreadPool> own_;
  ThreadPool* pool_;
};

double mean_of(const std::vector<float>& values) {
  double sum = 0.0;
  for (float v : values) sum += v;
  return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

Image error_image(int width, int height) {
  Image map;
  map.width = width;
  map.height = height;
  map.channels = {"FLIP"};
  map.values.resize(map.pixel_count());
  return map;
}

}  // namespace

FlipResult flip_ldr(const Image& reference, const Image& test, const FlipOptions& options, ThreadPool* pool) {
  check_pair(reference, test, options);
  const ColourView views[2] = {colour_view(reference, "reference"), colour_view(test, "test")};
  const SrgbDecoder decode;
  // Decoded to linear RGB and clamped to [0, 1], as the tool does with its inputs.
  const auto source = [&](const ColourView& view) {
    return [&view, &decode](int y, float* r, float* g, float* b) {
      for (int x = 0; x < view.width; ++x) {
        r[x] = clamp01(decode(view.at(x, y, 0)));
        g[x] = clamp01(decode(view.at(x, y, 1)));
        b[x] = clamp01(decode(view.at(x, y, 2)));
      }
    };
  };
  PoolChoice threads(pool);
  FlipResult result;
  result.error_map = error_image(reference.width, reference.height);
  flip_detail::FlipPipeline pipeline(reference.width, reference.height, options.pixels_per_degree);
  const double pixels = static_cast<double>(reference.width) * static_cast<double>(reference.height);
  result.complete = pipeline.run(source(views[0]), source(views[1]), result.error_map.values.data(), *threads,
                                 options.stop_when_mean_exceeds * pixels);
  result.mean = mean_of(result.error_map.values);
  return result;
}

FlipResult flip_hdr(const Image& reference, const Image& test, const FlipOptions& options, ThreadPool* pool) {
  check_pair(reference, test, options);
  const ColourView views[2] = {colour_view(reference, "reference"), colour_view(test, "test")};

  FlipResult result;
  float start = static_cast<float>(options.start_exposure), stop = static_cast<float>(options.stop_exposure);
  if (options.automatic_exposures) automatic_exposures(reference, views[0], start, stop);
  if (!std::isfinite(start) || !std::isfinite(stop) || start > stop)
    throw std::invalid_argument("FLIP: the start exposure must not exceed the stop exposure (" +
                                std::to_string(start) + " > " + std::to_string(stop) + ")");
  if (options.exposure_count < 0) throw std::invalid_argument("FLIP: the exposure count must not be negative");
  const int count = options.exposure_count > 0 ? options.exposure_count
                                               : static_cast<int>(std::max(2.0f, std::ceil(stop - start)));
  const float step = count > 1 ? (stop - start) / static_cast<float>(count - 1) : 0.0f;

  PoolChoice threads(pool);
  result.error_map = error_image(reference.width, reference.height);
  std::vector<float> exposure_error(result.error_map.values.size());
  flip_detail::FlipPipeline pipeline(reference.width, reference.height, options.pixels_per_degree);
  for (int i = 0; i < count; ++i) {
    const float scale = std::pow(2.0f, start + static_cast<float>(i) * step);
    // Exposed, tone mapped and clamped: LDR-FLIP's linear input.
    const auto source = [&](const ColourView& view) {
      return [&view, scale](int y, float* r, float* g, float* b) {
        for (int x = 0; x < view.width; ++x) {
          r[x] = clamp01(aces(scale * view.at(x, y, 0)));
          g[x] = clamp01(aces(scale * view.at(x, y, 1)));
          b[x] = clamp01(aces(scale * view.at(x, y, 2)));
        }
      };
    };
    pipeline.run(source(views[0]), source(views[1]), exposure_error.data(), *threads);
    std::vector<float>& best = result.error_map.values;
    for (std::size_t p = 0; p < best.size(); ++p) best[p] = std::max(best[p], exposure_error[p]);
  }
  result.mean = mean_of(result.error_map.values);
  result.start_exposure = start;
  result.stop_exposure = stop;
  result.exposure_count = count;
  return result;
}

}  // namespace farm
