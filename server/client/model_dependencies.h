#pragma once
// The files a model file reads besides itself, so a job sent to a farm carries everything its
// loaders will open: an OBJ's material libraries (and the maps they name), a glTF's external
// buffers and images, a COLLADA file's images. References to files that do not exist are left
// out: the loaders treat those the same way on every machine.
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace farm {

// Finds the dependencies of many models, reading each file once. A job names the same model
// for every copy of it (a field of 100 cows is one cow.dae), and OBJs often share a material
// library: a scanner remembers what each file references, so a submission reads each model and
// library once however many objects use it. What it remembers is never re-checked, so a scanner
// lives as long as one submission, not longer.
class ModelDependencyScanner {
 public:
  // Absolute, normalised paths of the existing files `model` references (not `model` itself),
  // sorted, without duplicates. The first call for a path reads the file; later calls return
  // what it found. Throws InputError naming the model when it cannot be read.
  const std::vector<std::filesystem::path>& dependencies(const std::filesystem::path& model);

  // Files read so far to find references: models and the OBJ material libraries they name.
  std::size_t files_scanned() const { return files_scanned_; }

 private:
  using Paths = std::vector<std::filesystem::path>;

  std::string read(const std::filesystem::path& file, const char* what);
  Paths scan_model(const std::filesystem::path& model);
  Paths scan_obj(const std::filesystem::path& model);
  // The maps an MTL file names; kept apart from models_ because a library is read as MTL
  // whatever its extension.
  const Paths& material_library_maps(const std::filesystem::path& library);

  std::map<std::filesystem::path, Paths> models_;
  std::map<std::filesystem::path, Paths> material_libraries_;
  std::size_t files_scanned_ = 0;
};

// The same for one model, with nothing remembered.
std::vector<std::filesystem::path> model_dependencies(const std::filesystem::path& model);

}  // namespace farm
