#pragma once
// The loader targets' one step: the input as a model file of the given extension in the scratch
// folder, loaded by load_model as `farm render` loads a job's model, confined to that folder (so
// a reference in the model to another file is refused or missing, as for a user's model).
// Bad input must come out as InputError; anything else escapes to libFuzzer as a crash.
#include <optional>
#include <string>
#include <string_view>

#include "renderer/scene/model.h"
#include "renderer/util/input_error.h"
#include "tests/fuzz/fuzz_support.h"

namespace farm::fuzz {

// A loaded model's animations pose it without an error (model_animation.h: the loader refuses
// what node_world_matrices and rest_to_posed_matrices would), at times before, on, between and
// after the keys.
inline void pose_every_animation(const Model& model) {
  for (const Mesh& mesh : model.meshes) {
    if (mesh.node < -1 || mesh.node >= static_cast<int>(model.nodes.size())) {
      property_failed("a mesh's node is missing");
    }
  }
  for (const ModelAnimation& animation : model.animations) {
    const double end = animation.end_seconds();
    for (const double t : {-1.0, 0.0, end / 3, end, end + 1}) {
      const auto to_posed = rest_to_posed_matrices(model, &animation, t);
      for (const Mesh& mesh : model.meshes) (void)mesh_rest_to_posed(mesh, to_posed);
    }
  }
}

inline void load_model_bytes(std::string_view bytes, const std::string& extension) {
  const auto file = write_scratch_file("model" + extension, bytes);
  std::optional<Model> loaded;
  try {
    loaded = load_model(file, scratch_dir());
    const Model& model = *loaded;
    // What load_model promises of a model it returns (model.h, finish_loaded_model).
    if (model.triangle_count() == 0) property_failed("a loaded model without triangles");
    for (const Mesh& mesh : model.meshes) {
      if (mesh.material >= model.materials.size()) property_failed("a mesh's material is missing");
      if (mesh.normals.size() != mesh.positions.size()) property_failed("a mesh without a normal a position");
      for (const auto& t : mesh.triangles) {
        if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size()) {
          property_failed("a triangle indexes past its mesh's positions");
        }
      }
    }
  } catch (const InputError&) {
    return;
  }
  pose_every_animation(*loaded);  // outside the try: an InputError here is a failure
}

}  // namespace farm::fuzz
