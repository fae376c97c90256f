// TEMPORARY: lets the bvh branch link until the Embree intersector lands; delete at merge.
#include <stdexcept>

#include "renderer/geometry/embree_intersector.h"

namespace farm {

std::unique_ptr<SceneIntersector> build_embree_intersector(const PreparedScene&) {
  throw std::logic_error("build_embree_intersector: not built on the bvh branch (TEMP stub)");
}

}  // namespace farm
