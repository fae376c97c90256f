#include "renderer/trace/sampler.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace farm {
namespace {

// The numbers every path-traced image is made of, written out as the sampler defines them: three
// mixes of (seed, pixel, sample and dimension), the top 24 bits as a fraction. PixelSamples
// works the first two out once a pixel; it must give these bits for every sample and dimension.
float reference_uniform(std::uint64_t seed, std::uint64_t pixel, std::uint32_t sample, std::uint32_t dimension) {
  std::uint64_t h = mix64(seed ^ 0x9e3779b97f4a7c15ULL);
  h = mix64(h ^ pixel);
  h = mix64(h ^ ((static_cast<std::uint64_t>(sample) << 32) | dimension));
  return static_cast<float>(h >> 40) / 16777216.0f;
}

TEST(Sampler, PixelSamplesGiveTheNumbersOfTheWholeHash) {
  for (std::uint64_t seed : {0ULL, 1ULL, 0xfeedULL, ~0ULL}) {
    for (std::uint64_t pixel : {0ULL, 7ULL, 1920ULL * 1080ULL - 1ULL, 1ULL << 40}) {
      const PixelSamples samples(seed, pixel);
      for (std::uint32_t sample : {0u, 1u, 63u, 65535u, 0xffffffffu}) {
        for (std::uint32_t dimension = 0; dimension < 40; ++dimension) {
          const float expected = reference_uniform(seed, pixel, sample, dimension);
          ASSERT_EQ(samples.uniform(sample, dimension), expected) << seed << " " << pixel << " " << sample;
          ASSERT_EQ(sample_uniform(SampleKey{seed, pixel, sample}, dimension), expected);
          ASSERT_GE(expected, 0.0f);
          ASSERT_LT(expected, 1.0f);
        }
      }
    }
  }
}

// Different pixels, samples and dimensions do not share their numbers.
TEST(Sampler, NeighbouringKeysGiveDifferentNumbers) {
  const PixelSamples a(3, 100), b(3, 101);
  int same = 0;
  for (std::uint32_t d = 0; d < 1000; ++d) {
    same += a.uniform(0, d) == b.uniform(0, d);
    same += a.uniform(0, d) == a.uniform(1, d);
    same += a.uniform(0, d) == a.uniform(0, d + 1);
  }
  EXPECT_LE(same, 2);  // 2^-24 odds each
}

}  // namespace
}  // namespace farm
