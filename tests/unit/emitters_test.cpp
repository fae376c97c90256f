// The emitters' pick (renderer/trace/emitters.h): first_above is std::upper_bound's answer
// exactly, found without branches, so the light a sample picks is the one the CDF says.
#include "renderer/trace/emitters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace farm {
namespace {

TEST(EmittersPick, FirstAboveIsUpperBoundForEveryLengthTiesAndEnds) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::uniform_int_distribution<int> coarse(0, 8);
  int checked = 0;
  for (int length = 0; length <= 70; ++length) {
    for (int trial = 0; trial < 40; ++trial) {
      // Sorted values, some equal (a zero-power emitter repeats the CDF's last entry).
      std::vector<float> sorted(static_cast<std::size_t>(length));
      for (float& v : sorted) v = trial % 2 ? static_cast<float>(coarse(rng)) / 8.0f : unit(rng);
      std::sort(sorted.begin(), sorted.end());
      std::vector<float> probes = {-1.0f, 0.0f, 1.0f, 2.0f};
      for (const float v : sorted) probes.insert(probes.end(), {v, std::nextafter(v, -1.0f), std::nextafter(v, 2.0f)});
      for (int i = 0; i < 20; ++i) probes.push_back(unit(rng));
      for (const float probe : probes) {
        const auto expected = static_cast<std::size_t>(std::upper_bound(sorted.begin(), sorted.end(), probe) - sorted.begin());
        ASSERT_EQ(first_above(sorted, probe), expected) << "length " << length << " probe " << probe;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100000);
}

}  // namespace
}  // namespace farm
