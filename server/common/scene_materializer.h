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
#include "renderer/scene/job.h"
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

// InputError unless every asset path is relative, free of ".." and NUL, unique, and every hash is
// 64 lowercase hex digits.
void validate_asset_refs(const v1::JobSpec& spec);

// InputError naming the asset's path when a blob the store holds is not as long as the AssetRef
// says (AssetRef.size must match the bytes). Blobs the store lacks are left to missing_assets.
void check_asset_sizes(const v1::JobSpec& spec, const AssetStore& store);

// The spec's assets whose blobs the store lacks (each hash once).
std::vector<v1::AssetRef> missing_assets(const v1::JobSpec& spec, const AssetStore& store);

struct MaterializedScene {
  std::filesystem::path dir;  // <cache>/scenes/<scene hash>
  Job job;                    // parsed with `dir` as the asset root
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

}  // namespace farm
