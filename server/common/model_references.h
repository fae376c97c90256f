#pragma once
// The files a model file names besides itself: an OBJ's material libraries and the maps they name
// (a library is read as MTL whatever its extension), a glTF's external buffers and images (a
// .glb's from its JSON chunk), a COLLADA file's images. PLY and the other formats name none.
// The one place that knows what each format names, so that the client gathering a job's files on
// disk (server/client/model_dependencies.h) and the scheduler planning a submission from the
// blobs it holds (server/scheduler/jobs/submission_plan.h) find the same files: a loader change
// is made here once. Where a reference leads, and whether its bytes can be read, is a
// ReferenceSource's: the client's confines it on disk, the scheduler's resolves it by name.
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace farm {

// What a model's bytes name, as written, by the model's extension: .obj its `mtllib` libraries,
// .gltf and .glb the uris of buffers and images, .dae the files its <image>s name; anything else
// names nothing. A model that does not parse names nothing here: its loader reports it.
std::vector<std::string> model_references(const std::filesystem::path& model, const std::string& bytes);
// MTL: the files of map_*, bump, disp, decal and refl (the statement's last word).
std::vector<std::string> material_library_maps(const std::string& text);

// A reference as written, as the local path it names: trimmed, `file://` dropped, '\' read as
// '/', %XX decoded. nullopt when it names no local file (empty, a data: URI, http:// and the like,
// which are never fetched).
std::optional<std::string> local_reference(std::string written);

// One reference a model or a library makes.
struct ModelReference {
  std::string written;  // as the file writes it, for messages
  std::string local;    // as local_reference reads it
};

// Where references lead and what files hold.
class ReferenceSource {
 public:
  virtual ~ReferenceSource() = default;
  // The file `reference` names as `referrer` (`model` itself, or a library it names) writes it:
  // its name, lexically normal under the root, where a farm lays it out. nullopt when there is
  // nothing to read there (no file: left out, as the loaders leave it out). InputError naming the
  // model and the reference when it is refused (absolute, out of the root, not a regular file).
  virtual std::optional<std::filesystem::path> locate(const std::filesystem::path& model,
                                                      const std::filesystem::path& referrer,
                                                      const ModelReference& reference) = 0;
  // The bytes of `file` (a model, or a file locate named); `what` ("model file", "material
  // library") for messages. nullopt when they are not to be had yet (a scheduler that does not
  // hold the blob): the file is then not scanned.
  virtual std::optional<std::string> read(const std::filesystem::path& file, const char* what) = 0;
};

// Finds the files of many models, reading each model and library once: a job names the same model
// for every copy of it (a field of 100 cows is one cow.dae), and OBJs often share a library. What
// it remembers is never checked again, so a scanner lives as long as one submission or one plan.
class ModelReferenceScanner {
 public:
  explicit ModelReferenceScanner(ReferenceSource& source) : source_(source) {}

  // The files `model` (a name under the root) references, not itself: those the source located,
  // sorted by name, each once. Throws what the source throws. A model, or a library of an OBJ,
  // whose bytes the source does not have is not scanned, and the model is scanned again by a later
  // call (its files found then are added).
  const std::vector<std::filesystem::path>& references(const std::filesystem::path& model);

  // Files read so far to find references: models and material libraries.
  std::size_t files_scanned() const { return files_scanned_; }

 private:
  using Files = std::vector<std::filesystem::path>;
  // The maps a library names; nullopt when its bytes are not to be had.
  const Files* library_maps(const std::filesystem::path& model, const std::filesystem::path& library);
  std::optional<std::string> read(const std::filesystem::path& file, const char* what);
  // The local files among `written` (references `referrer` makes, for `model`) that the source
  // locates, in the order written.
  Files locate_each(const std::filesystem::path& model, const std::filesystem::path& referrer,
                    std::vector<std::string> written);

  ReferenceSource& source_;
  std::map<std::filesystem::path, Files> models_;     // scanned whole
  std::map<std::filesystem::path, Files> libraries_;  // read as MTL whatever their extension
  Files partial_;  // what a model not scanned whole references, until the next call
  std::size_t files_scanned_ = 0;
};

}  // namespace farm
