#pragma once
// Counter-based random numbers (docs/architecture.md, "The engine contract"): a value is a pure function of
// (seed, frame, pixel, sample index,
// dimension), so an image never depends on tiling, threads or retries.
#include <cstdint>

#include "renderer/util/mix64.h"

namespace farm {

// The seed a frame's random numbers are keyed by: the job's seed itself at frame 0 (a still), so
// that a frame range leaves a still's pixels as they were, and one mixed with the frame number
// otherwise, so that frames do not share their noise.
inline std::uint64_t frame_seed(std::uint64_t seed, int frame) {
  if (frame == 0) return seed;
  return mix64(seed ^ mix64(0xd1b54a32d192ed03ULL + static_cast<std::uint64_t>(frame)));
}

struct SampleKey {
  std::uint64_t seed;
  std::uint64_t pixel;  // y * width + x
  std::uint32_t sample;
};

// A pixel's random numbers, the part of their hash that only the seed and the pixel feed worked
// out once for all its samples and dimensions (the path tracer asks several a bounce; before,
// the compiler hoisted most of it, not all: 1% of the Cornell box's instructions).
// uniform(s, d) is the number of sample s, dimension d.
class PixelSamples {
 public:
  PixelSamples(std::uint64_t seed, std::uint64_t pixel)
      : pixel_hash_(mix64(mix64(seed ^ 0x9e3779b97f4a7c15ULL) ^ pixel)) {}
  // Uniform in [0, 1). Always inlined: a multiply or two, called several times a bounce, whose
  // call the engines' grown loops must not pay.
  [[gnu::always_inline]] float uniform(std::uint32_t sample, std::uint32_t dimension) const {
    return unit_float(mix64(pixel_hash_ ^ ((static_cast<std::uint64_t>(sample) << 32) | dimension)));
  }

 private:
  std::uint64_t pixel_hash_;
};

// Uniform in [0, 1), for dimension `dimension` of one sample (PixelSamples's number).
[[gnu::always_inline]] inline float sample_uniform(const SampleKey& key, std::uint32_t dimension) {
  return PixelSamples(key.seed, key.pixel).uniform(key.sample, dimension);
}

}  // namespace farm
