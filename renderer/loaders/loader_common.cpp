// Steps shared by the Assimp and glTF loaders: baking node transforms and the final checks.
#include <cmath>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <string>
#include <utility>
#include <vector>

#include "renderer/loaders/loaders.h"
#include "renderer/scene/transform.h"
#include "renderer/texture/material_textures.h"
#include "renderer/util/input_error.h"

namespace farm {

ConfinedFile confine_loader_path(const ModelFile& model, const std::string& path) {
  const std::string folder = model.file.resolved.parent_path().string();
  const std::string prefix = folder == "/" ? folder : folder + "/";
  const std::string reference = path.rfind(prefix, 0) == 0 ? path.substr(prefix.size()) : path;
  return confine_file(model.root, model.file.resolved, reference);
}

void bake_node_transform(Mesh& mesh, const glm::mat4& node_to_root) {
  for (glm::vec3& p : mesh.positions) p = glm::vec3(node_to_root * glm::vec4(p, 1.0f));

  const glm::mat3 normal_to_root = normal_matrix(node_to_root);
  bool normals_usable = mesh.normals.size() == mesh.positions.size();
  for (glm::vec3& n : mesh.normals) {
    n = normal_to_root * n;
    const float len = glm::length(n);
    if (!(len > 0.0f) || !std::isfinite(len)) {
      normals_usable = false;
      break;
    }
    n /= len;
  }
  // A singular transform or a zero normal in the file: regenerate rather than keep garbage.
  if (!normals_usable) mesh.normals.clear();

  // Tangents lie in the surface: carried by the transform itself. Under a mirroring transform the
  // bitangent, a cross product with the normal, would flip: w flips with it.
  const glm::mat3 linear(node_to_root);
  const float handedness = glm::determinant(linear) < 0.0f ? -1.0f : 1.0f;
  for (glm::vec4& t : mesh.tangents) {
    const glm::vec3 moved = linear * glm::vec3(t);
    const float len = glm::length(moved);
    if (!(len > 0.0f) || !std::isfinite(len)) {
      mesh.tangents.clear();  // made again from the uvs where a normal map needs them
      break;
    }
    t = glm::vec4(moved / len, t.w * handedness);
  }

  if (glm::determinant(glm::mat3(node_to_root)) < 0.0f) {
    for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
  }
}

void finish_loaded_model(Model& model) {
  const std::string file = model.source.string();
  if (model.materials.empty()) model.materials.emplace_back();
  // Meshes left empty (a node holding only points or lines) would only be noise downstream.
  std::erase_if(model.meshes, [](const Mesh& m) { return m.triangles.empty(); });

  for (Mesh& mesh : model.meshes) {
    for (const glm::vec3& p : mesh.positions) {
      if (!all_finite(p)) {
        throw InputError(file + ": mesh '" + mesh.name + "' has a vertex that is not finite");
      }
    }
    for (const glm::uvec3& t : mesh.triangles) {
      const std::size_t n = mesh.positions.size();
      if (t.x >= n || t.y >= n || t.z >= n) {
        throw InputError(file + ": mesh '" + mesh.name + "' has a triangle index out of range");
      }
    }
    if (mesh.normals.size() != mesh.positions.size()) generate_smooth_normals(mesh);
    if (mesh.material >= model.materials.size()) mesh.material = 0;
    // A normal map needs a tangent frame: the file's, or one made from the uvs.
    const Material& material = model.materials[mesh.material];
    if (material.textures && material.textures->normal && mesh.tangents.size() != mesh.positions.size()) {
      mesh.tangents.clear();
      generate_tangents(mesh);
    }
  }

  if (model.triangle_count() == 0) throw InputError(file + ": the file contains no triangles");
}

}  // namespace farm
