// load_model: checks that the file is there and readable, then hands it to the loader for its
// extension. Every failure is an InputError that names the file.
#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>
#include <system_error>

#include "renderer/scene/input_error.h"
#include "renderer/scene/loaders.h"
#include "renderer/scene/model.h"

namespace farm {
namespace {

constexpr const char* kSupported = ".dae .obj .ply .gltf .glb";

std::string lowercase_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

void require_readable_file(const std::filesystem::path& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(status)) {
    throw InputError(file.string() + ": model file not found");
  }
  if (!std::filesystem::is_regular_file(status)) {
    throw InputError(file.string() + ": not a regular file");
  }
  // The importers report an unreadable file with messages that do not always name it.
  if (!std::ifstream(file, std::ios::binary)) {
    throw InputError(file.string() + ": model file cannot be read");
  }
}

}  // namespace

Model load_model(const std::filesystem::path& file) {
  const std::string ext = lowercase_extension(file);
  const bool assimp = ext == ".dae" || ext == ".obj" || ext == ".ply";
  const bool gltf = ext == ".gltf" || ext == ".glb";
  if (!assimp && !gltf) {
    throw InputError(file.string() + ": unsupported model format '" + ext +
                     "' (supported: " + kSupported + ")");
  }
  require_readable_file(file);
  return assimp ? load_with_assimp(file) : load_gltf(file);
}

}  // namespace farm
