#pragma once
// Every object's materials as BSDFs, made once per frame (docs/architecture.md 8.1, "Prepared
// once"; kept in the frame cache): a material's BSDF depends on nothing but the material, yet the
// path tracer made one at every bounce, 4% of the Cornell box's instructions. A hit on its own
// material (no textures, which make a material per hit) that is not glass reads its BSDF here.
#include <vector>

#include "renderer/accel/scene_intersector.h"
#include "renderer/trace/bsdf.h"

namespace farm {

class PreparedScene;

class MaterialBsdfs {
 public:
  explicit MaterialBsdfs(const PreparedScene& scene);

  // The BSDF of the hit's own material (hit.material), as Bsdf(*hit.material, false) makes it.
  const Bsdf& opaque(const SurfaceHit& hit) const {
    const Object& object = objects_[hit.object];
    return object.bsdfs[static_cast<std::size_t>(hit.material - object.materials)];
  }

 private:
  struct Object {
    const Material* materials = nullptr;  // the object's first material: a hit's index is its offset
    std::vector<Bsdf> bsdfs;              // one per material, in order
  };
  std::vector<Object> objects_;  // one per scene object, in order
};

}  // namespace farm
