#pragma once
// Job spec + asset blobs -> a folder the existing loaders can read. The job's files are laid out
// under `<cache>/scenes/<scene hash>/<path as the job names it>` (hard links to the blobs, copies
// where the file system refuses links), the job JSON is written beside them, and the job is parsed
// with that folder as its asset root, so OBJ+MTL, glTF+bin and COLLADA load unchanged from disk.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/job/job.h"
#include "server/common/asset_store.h"

namespace farm {

// Assets a spec names whose blobs are not in the store (the services answer FAILED_PRECONDITION).
class MissingAssetsError : public std::runtime_error {
 public:
  explicit MissingAssetsError(std::vector<v1::AssetRef> missing);
  const std::vector<v1::AssetRef>& missing() const { return missing_; }

 protected:
  MissingAssetsError(std::vector<v1::AssetRef> missing, const std::string& message)
      : std::runtime_error(message), missing_(std::move(missing)) {}

 private:
  std::vector<v1::AssetRef> missing_;
};

// Assets whose blobs the store held damaged (their bytes no longer hash to their names): the
// blobs are removed, so uploading them again repairs the store; the services answer
// FAILED_PRECONDITION, as for missing ones.
class CorruptAssetsError : public MissingAssetsError {
 public:
  explicit CorruptAssetsError(std::vector<v1::AssetRef> corrupt);
};

// Bounds on a job's files: how many, and their paths' lengths (a file name's 255 bytes; the whole
// path short enough to lie under a data dir's scene folder within PATH_MAX).
inline constexpr int kMaxJobAssets = 10000;
inline constexpr std::size_t kMaxAssetPathBytes = 1024;
inline constexpr std::size_t kMaxFileNameBytes = 255;

// An asset path ("textures/wood.png") as it is laid out under a scene folder: lexically normal.
// InputError naming it unless it is relative, free of ".." and NUL, within the lengths above, and
// names a file.
std::filesystem::path checked_asset_path(const std::string& path);

// InputError unless there are at most kMaxJobAssets, every asset path is relative, free of ".."
// and NUL, within the lengths above, unique, and every hash is 64 lowercase hex digits.
void validate_asset_refs(const v1::JobSpec& spec);

// InputError naming the asset's path when a blob the store holds is not as long as the AssetRef
// says (AssetRef.size must match the bytes). Blobs the store lacks are left to missing_assets.
void check_asset_sizes(const v1::JobSpec& spec, const AssetStore& store);

// The spec's assets whose blobs the store lacks (each hash once).
std::vector<v1::AssetRef> missing_assets(const v1::JobSpec& spec, const AssetStore& store);

struct MaterializedScene {
  std::filesystem::path dir;       // <cache>/scenes/<scene hash>
  std::filesystem::path job_file;  // the job's text inside `dir`
  Job job;                         // parsed with `dir` as the asset root
};

// Lays out (once; the folder appears complete or not at all) and parses. InputError for bad asset
// refs, sizes that differ from the blobs', or a bad job (messages name spec.file_name, never the
// cache folder); MissingAssetsError when a blob is absent; CorruptAssetsError (the blobs removed)
// when a blob to be laid out, or one whose size differs from its ref's, fails its SHA-256; DiskFull
// when the disk has no room to lay it out (nothing is published). Safe to call concurrently, also
// from several processes on one cache.
MaterializedScene materialize_scene(const v1::JobSpec& spec, const std::string& scene_hash,
                                    const AssetStore& store,
                                    const std::filesystem::path& cache_dir);

// `message` (a loader's or parse_job's) naming the job as its author knows it: paths inside the
// scene folder relative to it, the folder itself as "the job's folder", never this machine's cache.
std::string without_scene_folder(std::string message, const std::filesystem::path& scene_dir);

}  // namespace farm
