#include <gtest/gtest.h>

#include "renderer/geometry/aabb.h"

namespace farm {

TEST(Aabb, EmptyBoxGrowsToContainPoints) {
  AABB box;
  EXPECT_TRUE(box.empty());
  box.grow(glm::vec3(1, 2, 3));
  box.grow(glm::vec3(-1, 0, 5));
  EXPECT_FALSE(box.empty());
  EXPECT_EQ(box.min, glm::vec3(-1, 0, 3));
  EXPECT_EQ(box.max, glm::vec3(1, 2, 5));
}

}  // namespace farm
