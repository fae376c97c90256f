// load_model: checks that the file lies in the root and is a regular file, then hands it to the
// loader for its extension. Every failure is an InputError that names the file.
#include <string>
#include <system_error>

#include "renderer/loaders/collada_check.h"
#include "renderer/loaders/loaders.h"
#include "renderer/loaders/ply_header.h"
#include "renderer/scene/model.h"
#include "renderer/util/file_extension.h"
#include "renderer/util/input_error.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSupported = ".dae .obj .ply .gltf .glb";

fs::path resolved_folder(const fs::path& folder) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(fs::absolute(folder), ec);
  if (ec) throw InputError(folder.string() + ": cannot resolve: " + ec.message());
  return resolved;
}

}  // namespace

Model load_model(const fs::path& file, const fs::path& asset_root) {
  const std::string ext = lowercase_extension(file);
  const bool assimp = ext == ".dae" || ext == ".obj" || ext == ".ply";
  const bool gltf = ext == ".gltf" || ext == ".glb";
  if (!assimp && !gltf) {
    throw InputError(file.string() + ": unsupported model format '" + ext +
                     "' (supported: " + kSupported + ")");
  }
  ModelFile model{file, {}, resolved_folder(asset_root)};
  std::error_code ec;
  const fs::path absolute = fs::absolute(file, ec);
  model.file = confine_file(model.root, absolute, absolute.string(), ReferenceForm::relative_or_absolute);
  if (model.file.verdict == Confinement::missing) throw InputError(file.string() + ": model file not found");
  if (!model.file.allowed()) throw InputError(file.string() + ": " + model.file.reason);
  // Assimp trusts a PLY header's element counts: they are held against the file's size first.
  if (ext == ".ply") check_ply_file(model.file, file.string());
  // Assimp trusts a COLLADA file's counts and index lists alike (collada_check.h).
  if (ext == ".dae") check_collada_file(model.file, file.string());
  return assimp ? load_with_assimp(model) : load_gltf(model);
}

Model load_model(const fs::path& file) {
  // The folder the model really lies in: `farm info link.obj` reads what the link points at.
  return load_model(file, resolved_folder(fs::absolute(file)).parent_path());
}

}  // namespace farm
