#include "renderer/scene/scene.h"

namespace farm {

std::size_t Scene::triangle_count() const {
  std::size_t n = 0;
  for (const SceneObject& o : objects) n += o.model ? o.model->triangle_count() : 0;
  return n;
}

}  // namespace farm
