#pragma once
// The loader targets' one step: the input as a model file of the given extension in the scratch
// folder, loaded by load_model as `farm render` loads a job's model, confined to that folder (so
// a reference in the model to another file is refused or missing, as for a user's model).
// Bad input must come out as InputError; anything else escapes to libFuzzer as a crash.
#include <string>
#include <string_view>

#include "renderer/scene/input_error.h"
#include "renderer/scene/model.h"
#include "tests/fuzz/fuzz_support.h"

namespace farm::fuzz {

inline void load_model_bytes(std::string_view bytes, const std::string& extension) {
  const auto file = write_scratch_file("model" + extension, bytes);
  try {
    const Model model = load_model(file, scratch_dir());
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
  }
}

}  // namespace farm::fuzz
