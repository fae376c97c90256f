#pragma once
// Bit-for-bit comparison of two frames, for tests that check a farm's image against `farm render`.
#include "renderer/image/tile_buffer.h"

namespace farm::test {

// Pixels whose bits differ in any channel either image has (RGBA and each AOV); -1 when the
// images do not cover the same rect, or are empty.
int differing_pixels(const TileBuffer& a, const TileBuffer& b);

}  // namespace farm::test
