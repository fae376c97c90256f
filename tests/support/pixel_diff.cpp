#include "tests/support/pixel_diff.h"

#include <cstring>

namespace farm::test {

namespace {

bool same_bits(const void* a, const void* b, std::size_t n) { return std::memcmp(a, b, n) == 0; }

bool same_aovs(const AovSet& a, const AovSet& b) {
  return a.depth == b.depth && a.normal == b.normal && a.albedo == b.albedo && a.bvh_cost == b.bvh_cost &&
         a.variance == b.variance;
}

}  // namespace

int differing_pixels(const TileBuffer& a, const TileBuffer& b) {
  if (!(a.rect() == b.rect()) || a.rect().empty() || !same_aovs(a.aovs(), b.aovs())) return -1;
  const AovSet& aovs = a.aovs();
  int differing = 0;
  for (int y = a.rect().y0; y < a.rect().y1; ++y) {
    for (int x = a.rect().x0; x < a.rect().x1; ++x) {
      const float da = aovs.depth ? a.depth(x, y) : 0.0f, db = aovs.depth ? b.depth(x, y) : 0.0f;
      const float ca = aovs.bvh_cost ? a.bvh_cost(x, y) : 0.0f, cb = aovs.bvh_cost ? b.bvh_cost(x, y) : 0.0f;
      if (!same_bits(&a.rgba(x, y), &b.rgba(x, y), sizeof(glm::vec4)) || !same_bits(&da, &db, sizeof da) ||
          !same_bits(&ca, &cb, sizeof ca) ||
          (aovs.normal && !same_bits(&a.normal(x, y), &b.normal(x, y), sizeof(glm::vec3))) ||
          (aovs.albedo && !same_bits(&a.albedo(x, y), &b.albedo(x, y), sizeof(glm::vec3))) ||
          (aovs.variance && !same_bits(&a.variance(x, y), &b.variance(x, y), sizeof(glm::vec3)))) {
        ++differing;
      }
    }
  }
  return differing;
}

}  // namespace farm::test
