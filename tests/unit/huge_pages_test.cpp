// Large arrays on huge pages (renderer/util/huge_pages.h): where they lie, what the kernel is
// asked for, and that a large BVH's nodes are such an array.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "renderer/geometry/bvh.h"
#include "renderer/util/huge_pages.h"

namespace farm {
namespace {

constexpr std::uintptr_t kTwoMiB = std::uintptr_t{2} << 20;

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// The kernel's transparent huge page mode: "always", "madvise" or "never" (nullopt: no THP).
std::optional<std::string> thp_mode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(in, line)) return std::nullopt;
  const auto open = line.find('['), close = line.find(']');
  if (open == std::string::npos || close == std::string::npos) return std::nullopt;
  return line.substr(open + 1, close - open - 1);
}

// /proc/self/smaps's THPeligible for the mapping holding p (nullopt: the kernel does not say).
std::optional<int> thp_eligible(const void* p) {
  std::ifstream in("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    unsigned long long begin = 0, end = 0;
    if (std::sscanf(line.c_str(), "%llx-%llx ", &begin, &end) == 2 && line.find(':') > line.find('-')) {
      inside = address(p) >= begin && address(p) < end;
      continue;
    }
    int eligible = 0;
    if (inside && std::sscanf(line.c_str(), "THPeligible: %d", &eligible) == 1) return eligible;
  }
  return std::nullopt;
}

// Where the kernel offers huge pages for madvised memory, the mapping at p is eligible: the
// advice was given (with "madvise", the mode Debian ships, nothing else makes it so).
void expect_offered_huge_pages(const void* p) {
  const std::optional<std::string> mode = thp_mode();
  if (!mode || *mode == "never") return;
  const std::optional<int> eligible = thp_eligible(p);
  if (!eligible) return;  // a kernel older than 5.0 does not report it
  EXPECT_EQ(*eligible, 1) << "THP mode " << *mode;
}

TEST(LargeArrayAllocator, ArraysFromFourMebibytesLieOnHugePageBoundariesAndAskForHugePages) {
  std::vector<float, LargeArrayAllocator<float>> big(std::size_t{5} << 20 >> 2, 1.0f);
  EXPECT_EQ(address(big.data()) % kTwoMiB, 0u);
  expect_offered_huge_pages(big.data());
  EXPECT_EQ(large_array_size((std::size_t{4} << 20) + 1), std::size_t{6} << 20);
  EXPECT_EQ(large_array_size(std::size_t{4} << 20), std::size_t{4} << 20);
  EXPECT_EQ(large_array_size(100 * 1024 + 1), 104u * 1024) << "under 4 MiB: whole 4 KiB pages";
}

TEST(LargeArrayAllocator, KeepsEveryValueAsAnArrayGrowsFromTheHeapOntoHugePages) {
  std::vector<std::uint32_t, LargeArrayAllocator<std::uint32_t>> values;
  for (std::uint32_t i = 0; i < (3u << 20); ++i) values.push_back(i * 2654435761u);
  ASSERT_GE(values.size() * sizeof(std::uint32_t), std::size_t{4} << 20);
  EXPECT_EQ(address(values.data()) % kTwoMiB, 0u);
  for (std::uint32_t i = 0; i < values.size(); ++i) ASSERT_EQ(values[i], i * 2654435761u) << i;
  values.resize(10);
  values.shrink_to_fit();  // back to the heap
  EXPECT_EQ(values[9], 9u * 2654435761u);
}

TEST(LargeArrayAllocator, ALargeTreesWideNodesLieOnHugePages) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> at(-100.0f, 100.0f), size(0.0f, 0.5f);
  std::vector<AABB> boxes(600'000);
  for (AABB& b : boxes) {
    const glm::vec3 lo{at(rng), at(rng), at(rng)};
    b.grow(lo);
    b.grow(lo + glm::vec3(size(rng), size(rng), size(rng)));
  }
  const Bvh bvh = Bvh::build(boxes, {BvhSplit::Sah, 4, nullptr, 4});
  ASSERT_GE(bvh.wide_nodes().size_bytes(), std::size_t{4} << 20);
  EXPECT_EQ(address(bvh.wide_nodes().data()) % kTwoMiB, 0u);
  expect_offered_huge_pages(bvh.wide_nodes().data());
}

}  // namespace
}  // namespace farm
