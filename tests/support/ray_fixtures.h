#pragma once
// Deterministic random rays and triangle soups for acceleration-structure tests.
#include <cstdint>
#include <vector>

#include "renderer/geometry/aabb.h"
#include "renderer/geometry/ray.h"
#include "renderer/scene/model.h"

namespace farm::test {

// A mix, from a fixed seed: origins inside `bounds` with directions uniform on the sphere;
// origins outside aimed at a random point of `bounds`; and axis-parallel rays (exact zero
// direction components), some with an origin coordinate on one of `planes` (e.g. vertex
// coordinates, so rays lie in axis-aligned walls). Direction lengths vary (t is in units of
// |direction|).
std::vector<Ray> random_rays(const AABB& bounds, std::size_t count, std::uint32_t seed,
                             const std::vector<glm::vec3>& planes = {});

// `count` random triangles in [-1, 1]^3: sizes over three orders of magnitude, slivers,
// axis-aligned flat triangles on a few shared planes, exact duplicates and a shared-vertex
// strip, so ties and flat boxes occur. Normals are the faces' (de-indexed).
Model random_soup(std::size_t count, std::uint32_t seed);

}  // namespace farm::test
