#pragma once
// Line drawings over an image, for the lab's "Show BVH": the edges of boxes given in some
// object's space, projected through the camera and drawn one pixel wide in a level's colour.
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "renderer/geometry/aabb.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/scene/camera.h"

namespace farm {

class BoxOverlay {
 public:
  // Draws into `image`, whose rect is the whole frame of the camera's view.
  BoxOverlay(TileBuffer& image, const Camera& camera);

  // The 12 edges of `box` (in the space `to_world` maps from), clipped at the near plane.
  void draw_box(const AABB& box, const glm::mat4& to_world, const glm::vec3& color);

  // A distinct colour per BVH level, cycling.
  static glm::vec3 level_color(int level);

 private:
  void draw_segment(glm::vec3 a_world, glm::vec3 b_world, const glm::vec3& color);

  TileBuffer& image_;
  const Camera& camera_;
  glm::mat4 view_{1.0f}, projection_{1.0f};
};

}  // namespace farm
