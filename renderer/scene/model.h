#pragma once
// Everything one model file contributes: meshes (model space), materials, and the cameras and
// lights it declares, which a job uses only when it gives none of its own; from glTF also the node
// hierarchy and the animations that move it (renderer/scene/model_animation.h).
#include <filesystem>
#include <string>
#include <vector>

#include "renderer/scene/camera.h"
#include "renderer/scene/light.h"
#include "renderer/scene/material.h"
#include "renderer/scene/mesh.h"
#include "renderer/scene/model_animation.h"

namespace farm {

struct Model {
  std::filesystem::path source;
  std::vector<Mesh> meshes;
  std::vector<Material> materials;  // never empty after loading: a default is added if needed
  std::vector<Camera> cameras;
  std::vector<Light> lights;
  std::vector<ModelNode> nodes;            // glTF only: every node of the file, in its order
  std::vector<ModelAnimation> animations;  // glTF only

  std::size_t triangle_count() const;
  std::size_t vertex_count() const;
  AABB bounds() const;
};

// Loads .dae/.obj/.ply (Assimp) and .gltf/.glb (tinygltf). Throws InputError naming the file and
// what is wrong with it; never crashes on malformed input. The model and every file it names (an
// OBJ's material libraries, a glTF's buffers and images) must lie in `asset_root` as
// renderer/util/confined_file.h says: a reference that is absolute, leads out, or names no
// regular file is an InputError naming the model and the reference, and is never opened.
Model load_model(const std::filesystem::path& file, const std::filesystem::path& asset_root);
// The same with the model's own folder as the root (`farm info`, benchmarks).
Model load_model(const std::filesystem::path& file);

}  // namespace farm
