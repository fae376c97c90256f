#include "renderer/trace/material_bsdfs.h"

#include "renderer/accel/prepared_scene.h"

namespace farm {

MaterialBsdfs::MaterialBsdfs(const PreparedScene& scene) {
  objects_.reserve(scene.objects().size());
  for (const PreparedObject& prepared : scene.objects()) {
    const std::vector<Material>& materials = prepared.source->materials;
    Object& object = objects_.emplace_back();
    object.materials = materials.data();
    object.bsdfs.reserve(materials.size());
    for (const Material& material : materials) object.bsdfs.emplace_back(material, false);
  }
}

}  // namespace farm
