#pragma once
#include <cstdint>

namespace farm {

// Work one ray did in an acceleration structure: the `bvh_cost` AOV is nodes + triangles.
struct TraversalStats {
  std::uint64_t nodes = 0;
  std::uint64_t triangles = 0;

  std::uint64_t cost() const { return nodes + triangles; }
};

}  // namespace farm
