#pragma once
// Sub-pixel sample positions for supersampling (spp > 1): sample 0 is the pixel centre, later
// ones follow the Halton (2, 3) sequence, so every pixel uses the same well-spread pattern and
// the image does not depend on tiling.
#include "renderer/raster/edge_function.h"

namespace farm::raster {

inline double radical_inverse(int index, int base) {
  double result = 0.0, digit_weight = 1.0 / base;
  for (int i = index; i > 0; i /= base, digit_weight /= base) result += (i % base) * digit_weight;
  return result;
}

// Offset of sample `index` inside its pixel, in fixed-point units [0, kSubpixelScale).
inline FixedPoint sample_offset(int index) {
  if (index == 0) return {kSubpixelScale / 2, kSubpixelScale / 2};
  const auto fixed = [](double u) {
    return static_cast<std::int64_t>(u * static_cast<double>(kSubpixelScale));
  };
  return {fixed(radical_inverse(index, 2)), fixed(radical_inverse(index, 3))};
}

}  // namespace farm::raster
