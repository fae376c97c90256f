#include "renderer/scene/model.h"

namespace farm {

std::size_t Model::triangle_count() const {
  std::size_t n = 0;
  for (const Mesh& m : meshes) n += m.triangle_count();
  return n;
}

std::size_t Model::vertex_count() const {
  std::size_t n = 0;
  for (const Mesh& m : meshes) n += m.positions.size();
  return n;
}

AABB Model::bounds() const {
  AABB box;
  for (const Mesh& m : meshes) box.grow(m.bounds());
  return box;
}

}  // namespace farm
