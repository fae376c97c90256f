#pragma once
// The files a model file reads besides itself, so a job sent to a farm carries everything its
// loaders will open: an OBJ's material libraries (and the maps they name), a glTF's external
// buffers and images, a COLLADA file's images. What each format names is read by the code the
// scheduler plans submissions with (server/common/model_references.h); here the references are
// resolved on disk. References to files that do not exist are left out: the loaders treat those
// the same way on every machine.
#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "renderer/util/confined_file.h"
#include "server/common/model_references.h"

namespace farm {

// Finds the dependencies of many models, reading each file once (ModelReferenceScanner): a
// submission reads each model and library once however many objects use it. What it remembers
// is never re-checked, so a scanner lives as long as one submission, not longer.
//
// Every reference passes confine_file (renderer/util/confined_file.h), the gate the loaders use on
// the scheduler and the workers, before anything reads it: a reference that is absolute, leads
// out of the asset root, or names no regular file is an InputError naming the model and the
// reference, and that file is neither read nor sent.
class ModelDependencyScanner {
 public:
  // `asset_root`: the folder every model and every file they name must lie in.
  explicit ModelDependencyScanner(std::filesystem::path asset_root);
  ~ModelDependencyScanner();

  // The existing files `model` references (not `model` itself), allowed by confine_file: `named`
  // as the model names them (the path a farm lays them out at), `resolved` to read. Sorted by
  // name, without duplicates. The first call for a path reads the file; later calls return what it
  // found. Throws InputError naming the model when it cannot be read or a reference is refused.
  const std::vector<ConfinedFile>& dependencies(const std::filesystem::path& model);

  // Files read so far to find references: models and the OBJ material libraries they name.
  std::size_t files_scanned() const { return scanner_.files_scanned(); }

 private:
  class OnDisk;  // the ReferenceSource: confine_file and read_confined

  std::unique_ptr<OnDisk> disk_;
  ModelReferenceScanner scanner_;
  std::map<std::filesystem::path, std::vector<ConfinedFile>> models_;
};

// The same for one model, with nothing remembered, confined to the folder it lies in.
std::vector<ConfinedFile> model_dependencies(const std::filesystem::path& model);

}  // namespace farm
