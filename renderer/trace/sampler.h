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

// Uniform in [0, 1), for dimension `dimension` of one sample. Always inlined: a few multiplies,
// called several times a bounce, whose call the engines' grown loops must not pay.
[[gnu::always_inline]] inline float sample_uniform(const SampleKey& key, std::uint32_t dimension) {
  std::uint64_t h = mix64(key.seed ^ 0x9e3779b97f4a7c15ULL);
  h = mix64(h ^ key.pixel);
  h = mix64(h ^ ((static_cast<std::uint64_t>(key.sample) << 32) | dimension));
  return unit_float(h);
}

}  // namespace farm
