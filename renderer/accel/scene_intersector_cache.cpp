#include <string>

#include "renderer/accel/prepared_scene.h"
#include "renderer/accel/scene_intersector.h"

namespace farm {

std::shared_ptr<const SceneIntersector> cached_scene_intersector(const PreparedScene& scene,
                                                                 AccelKind accel,
                                                                 const CancelFlag& cancel) {
  return scene.frame_cache().get_or_build<SceneIntersector>(
      "intersector " + std::string(to_string(accel)), cancel,
      [&] { return std::shared_ptr<const SceneIntersector>(build_scene_intersector(scene, accel, cancel)); });
}

}  // namespace farm
