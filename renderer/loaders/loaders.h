#pragma once
// Internal to the scene loaders (not part of the renderer's API): one entry point per file
// family, which load_model picks by extension, and the steps every loader shares.
#include <cmath>
#include <filesystem>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <string>

#include "renderer/scene/model.h"
#include "renderer/util/confined_file.h"

namespace farm {

// A model file as load_model hands it to a loader: checked by confine_file, with the root that
// every file it names is confined to.
struct ModelFile {
  std::filesystem::path name;  // as the caller named it: for messages and Model::source
  ConfinedFile file;           // allowed: file.resolved is what is read
  std::filesystem::path root;  // canonical
};

Model load_with_assimp(const ModelFile& model);  // .dae .obj .ply
Model load_gltf(const ModelFile& model);         // .gltf .glb

// A file the loader libraries ask for, confined to the model's root. Assimp and tinygltf join the
// model's folder and the reference as written ("/m/" + "../x.mtl", "/m/" + "/etc/passwd"), so what
// follows the folder is the reference; any other path is taken as a reference in itself.
ConfinedFile confine_loader_path(const ModelFile& model, const std::string& path);

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
