#pragma once
// The files a model file reads besides itself, so a job sent to a farm carries everything its
// loaders will open: an OBJ's material libraries (and the maps they name), a glTF's external
// buffers and images, a COLLADA file's images. References to files that do not exist are left
// out: the loaders treat those the same way on every machine.
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "renderer/util/confined_file.h"

namespace farm {

// Finds the dependencies of many models, reading each file once. A job names the same model
// for every copy of it (a field of 100 cows is one cow.dae), and OBJs often share a material
// library: a scanner remembers what each file references, so a submission reads each model and
// library once however many objects use it. What it remembers is never re-checked, so a scanner
// lives as long as one submission, not longer.
//
// Every reference passes confine_file (renderer/util/confined_file.h), the gate the loaders use on
// the scheduler and the workers, before anything reads it: a reference that is absolute, leads
// out of the asset root, or names no regular file is an InputError naming the model and the
// reference, and that file is neither read nor sent.
class ModelDependencyScanner {
 public:
  // `asset_root`: the folder every model and every file they name must lie in.
  explicit ModelDependencyScanner(std::filesystem::path asset_root);

  // The existing files `model` references (not `model` itself), allowed by confine_file: `named`
  // as the model names them (the path a farm lays them out at), `resolved` to read. Sorted by
  // name, without duplicates. The first call for a path reads the file; later calls return what it
  // found. Throws InputError naming the model when it cannot be read or a reference is refused.
  const std::vector<ConfinedFile>& dependencies(const std::filesystem::path& model);

  // Files read so far to find references: models and the OBJ material libraries they name.
  std::size_t files_scanned() const { return files_scanned_; }

 private:
  using Files = std::vector<ConfinedFile>;

  std::string read(const ConfinedFile& file, const char* what);
  Files scan_model(const std::filesystem::path& model);
  Files scan_obj(const std::filesystem::path& model, const std::string& text);
  // The maps an MTL file names; kept apart from models_ because a library is read as MTL
  // whatever its extension.
  const Files& material_library_maps(const std::filesystem::path& model, const ConfinedFile& library);
  // A reference as written in `referrer`: nullopt when it names no local file or no file that
  // exists; InputError when refused.
  std::optional<ConfinedFile> reference(const std::filesystem::path& model, const std::filesystem::path& referrer,
                                        std::string written) const;

  std::filesystem::path root_;
  std::map<std::filesystem::path, Files> models_;
  std::map<std::filesystem::path, Files> material_libraries_;
  std::size_t files_scanned_ = 0;
};

// The same for one model, with nothing remembered, confined to the folder it lies in.
std::vector<ConfinedFile> model_dependencies(const std::filesystem::path& model);

}  // namespace farm
