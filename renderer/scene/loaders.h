#pragma once
// Internal to the scene loaders (not part of the renderer's API): one entry point per file
// family, which load_model picks by extension, and the steps every loader shares.
#include <cmath>
#include <filesystem>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "renderer/scene/model.h"

namespace farm {

Model load_with_assimp(const std::filesystem::path& file);  // .dae .obj .ply
Model load_gltf(const std::filesystem::path& file);         // .gltf .glb

// Moves a mesh from its node's space into the file's root space: positions by `node_to_root`,
// normals by its inverse transpose. Under a mirroring transform each triangle's corners are
// reordered, so that its winding (its geometric normal) still agrees with the shading normals.
void bake_node_transform(Mesh& mesh, const glm::mat4& node_to_root);

// The checks and repairs every loader ends with: meshes without usable normals get smooth ones,
// there is at least one material and every mesh points at a valid one, positions are finite, and
// the model has at least one triangle. Throws InputError naming `model.source` otherwise.
void finish_loaded_model(Model& model);

inline bool all_finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace farm
