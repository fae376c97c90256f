#pragma once
// Hashing for the random numbers the engines key by what they are for (docs/architecture.md,
// "The engine contract"): the same inputs give the same number on any thread and tiling.
#include <cstdint>

namespace farm {

// SplitMix64's finaliser: a bijective 64-bit mix with good avalanche.
inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A hash as a float uniform in [0, 1): its top 24 bits.
inline float unit_float(std::uint64_t h) { return static_cast<float>(h >> 40) * (1.0f / 16777216.0f); }

}  // namespace farm
