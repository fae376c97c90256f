// floats_to_halves against Imath's own software conversion (this file is built without F16C, so
// Imath::half(float) takes its bit-twiddling path): the same bits for every half's neighbourhood
// (each value, the float midpoints to its neighbours where ties round to even, one float either
// side of them), for a stride through every float bit pattern, and for strided, unaligned
// channels of every length around the eight-wide step. NaNs are left to a check of their own.
#include <gtest/gtest.h>

#include <Imath/half.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "renderer/image/float_to_half.h"

namespace farm {
namespace {

float from_bits(std::uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

std::uint32_t bits_of(float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

std::uint16_t reference(float f) { return Imath::half(f).bits(); }

// Converts `values` (packed) and returns the indices whose bits differ from Imath's.
std::vector<std::size_t> mismatches(const std::vector<float>& values) {
  std::vector<std::uint16_t> out(values.size());
  floats_to_halves(reinterpret_cast<const char*>(values.data()), sizeof(float), values.size(), out.data());
  std::vector<std::size_t> bad;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (out[i] != reference(values[i])) bad.push_back(i);
  }
  return bad;
}

TEST(FloatToHalf, EveryHalfItsTiesAndTheirNeighboursMatchImath) {
  std::vector<float> values;
  for (std::uint32_t h = 0; h < 0x10000; ++h) {
    Imath::half here;
    here.setBits(static_cast<std::uint16_t>(h));
    if (here.isNan()) continue;
    const float v = static_cast<float>(here);
    values.push_back(v);
    if (here.isInfinity()) continue;
    Imath::half next;
    next.setBits(static_cast<std::uint16_t>(h + 1));
    if (next.isNan()) continue;
    // The midpoint to the next half (a tie, exact in float), and one float either side.
    const float mid = (v + static_cast<float>(next)) / 2.0f;
    for (std::int64_t d = -1; d <= 1; ++d) {
      const float near = from_bits(static_cast<std::uint32_t>(bits_of(mid) + d));
      if (!std::isnan(near)) values.push_back(near);  // past the largest half's tie: infinity, then NaNs
    }
  }
  const std::vector<std::size_t> bad = mismatches(values);
  ASSERT_TRUE(bad.empty()) << bad.size() << " differ; first: float bits 0x" << std::hex << bits_of(values[bad[0]]);
}

TEST(FloatToHalf, AStrideThroughEveryFloatMatchesImath) {
  std::vector<float> values;
  for (std::uint64_t bits = 0; bits <= 0xffffffffu; bits += 997) {
    const float f = from_bits(static_cast<std::uint32_t>(bits));
    if (!std::isnan(f)) values.push_back(f);
  }
  const std::vector<std::size_t> bad = mismatches(values);
  ASSERT_TRUE(bad.empty()) << bad.size() << " differ; first: float bits 0x" << std::hex << bits_of(values[bad[0]]);
}

TEST(FloatToHalf, StridedUnalignedChannelsOfEveryLengthMatchImath) {
  // Five floats a pixel, one byte off alignment, the channel at its third float.
  constexpr std::size_t kStride = 5 * sizeof(float);
  for (std::size_t count = 0; count <= 40; ++count) {
    std::vector<char> bytes(1 + count * kStride);
    std::vector<float> expected(count);
    for (std::size_t i = 0; i < count; ++i) {
      expected[i] = 0.37f * static_cast<float>(i) - 3.0f + 1e-5f * static_cast<float>(i * i);
      std::memcpy(bytes.data() + 1 + i * kStride + 2 * sizeof(float), &expected[i], sizeof(float));
    }
    std::vector<std::uint16_t> out(count + 1, 0xabcd);
    floats_to_halves(bytes.data() + 1 + 2 * sizeof(float), kStride, count, out.data());
    for (std::size_t i = 0; i < count; ++i) EXPECT_EQ(out[i], reference(expected[i])) << count << " " << i;
    EXPECT_EQ(out[count], 0xabcd) << "wrote past the channel's end, count " << count;
  }
}

TEST(FloatToHalf, QuietNansStayNansAndInfinitiesStayInfinities) {
  const std::vector<float> values{std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN(),
                                  std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                                  1e6f, -1e6f};
  std::vector<float> eight_times;
  for (int k = 0; k < 8; ++k) eight_times.insert(eight_times.end(), values.begin(), values.end());  // the wide path too
  std::vector<std::uint16_t> out(eight_times.size());
  floats_to_halves(reinterpret_cast<const char*>(eight_times.data()), sizeof(float), eight_times.size(), out.data());
  for (std::size_t i = 0; i < out.size(); ++i) {
    Imath::half h;
    h.setBits(out[i]);
    if (std::isnan(eight_times[i])) {
      EXPECT_TRUE(h.isNan()) << i;
      EXPECT_EQ(out[i], reference(eight_times[i])) << i;  // a quiet NaN: the same bits
    } else {
      EXPECT_EQ(out[i], reference(eight_times[i])) << i;
    }
  }
}

}  // namespace
}  // namespace farm
