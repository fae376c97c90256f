#pragma once
// Synthetic image pairs for the comparison metrics' tests: a reference with smooth gradients,
// hard edges and texture, and variants of it (noise, a shift, a gain, hot pixels, an offset)
// that span clear passes and clear failures.
#include <cstdint>
#include <string>
#include <vector>

#include "renderer/compare/image.h"

namespace farm::test {

// A w x h RGB image in [0, 1] (display-like values), deterministic for `seed`.
Image synthetic_reference(int width, int height, std::uint32_t seed = 7);

struct Variant {
  std::string name;
  double noise = 0.0;        // standard deviation of added Gaussian noise
  int shift_x = 0;           // pixels the content moves right (the edge column repeats)
  double gain = 1.0;         // multiplies every value
  double offset = 0.0;       // added to every value
  int hot_pixels = 0;        // pixels set to 1 in every channel
  std::uint32_t seed = 11;
};

// `reference` changed as `variant` says; values are clamped to [0, 1] when `clamp`.
Image make_variant(const Image& reference, const Variant& variant, bool clamp = true);

}  // namespace farm::test
