#include "server/common/scene_materializer.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <set>
#include <system_error>

#include "renderer/util/atomic_file.h"
#include "renderer/util/input_error.h"
#include "server/common/disk_full.h"
#include "server/common/sha256.h"

namespace farm {

namespace fs = std::filesystem;

namespace {

constexpr const char* kDefaultJobName = "job.json";
constexpr std::size_t kMaxShown = 80;

std::string shown(const std::string& s) {
  return s.size() <= kMaxShown ? s : s.substr(0, kMaxShown) + "...";
}

std::string missing_message(const std::vector<v1::AssetRef>& missing) {
  std::string names;
  for (std::size_t i = 0; i < missing.size() && i < 5; ++i) {
    names += fmt::format("{}'{}' (sha256 {})", i ? ", " : "", shown(missing[i].path()),
                         missing[i].sha256());
  }
  if (missing.size() > 5) names += fmt::format(" and {} more", missing.size() - 5);
  return fmt::format("missing asset{} {}", missing.size() == 1 ? "" : "s", names);
}

std::string corrupt_message(const std::vector<v1::AssetRef>& corrupt) {
  std::string names;
  for (std::size_t i = 0; i < corrupt.size() && i < 5; ++i) {
    names += fmt::format("{}'{}' (sha256 {})", i ? ", " : "", shown(corrupt[i].path()), corrupt[i].sha256());
  }
  if (corrupt.size() > 5) names += fmt::format(" and {} more", corrupt.size() - 5);
  return fmt::format("asset{} {} stored damaged (the bytes no longer match the SHA-256) and removed: upload {} "
                     "again",
                     corrupt.size() == 1 ? "" : "s", names, corrupt.size() == 1 ? "it" : "them");
}

// Every blob of the spec that the store holds, hashed: damaged ones are removed and refused.
void refuse_corrupt_assets(const v1::JobSpec& spec, const AssetStore& store) {
  std::vector<v1::AssetRef> corrupt;
  std::set<std::string> seen;
  for (const v1::AssetRef& ref : spec.assets()) {
    if (!seen.insert(ref.sha256()).second || !store.has(ref.sha256())) continue;
    if (!store.intact(ref.sha256())) {
      store.remove(ref.sha256());
      corrupt.push_back(ref);
    }
  }
  if (!corrupt.empty()) throw CorruptAssetsError(std::move(corrupt));
}

// The path an asset is laid out at, relative to the scene folder; InputError if it could leave it.
fs::path checked_relative_path(const v1::AssetRef& ref) { return checked_asset_path(ref.path()); }

// The job file's name inside the scene folder: the name it was submitted under, so parse_job's
// messages read as they would for `farm render`, unless that is unusable or taken by an asset.
std::string job_file_name(const v1::JobSpec& spec, const std::set<fs::path>& asset_paths) {
  const fs::path given = fs::path(spec.file_name()).filename();
  const std::string name = given.string();
  if (!name.empty() && name != "." && name != ".." && name.find('\0') == std::string::npos &&
      name.size() <= kMaxFileNameBytes && !asset_paths.count(given)) {
    return name;
  }
  if (asset_paths.count(kDefaultJobName)) {
    throw InputError(fmt::format("asset path '{}' is reserved for the job file", kDefaultJobName));
  }
  return kDefaultJobName;
}

void replace_all(std::string& s, const std::string& from, const std::string& to) {
  if (from.empty()) return;
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
}

void link_or_copy(const fs::path& blob, const fs::path& to) {
  std::error_code ec;
  fs::create_hard_link(blob, to, ec);
  if (ec) fs::copy_file(blob, to);  // e.g. the cache and the blobs on different file systems
}

void lay_out(const v1::JobSpec& spec, const AssetStore& store, const fs::path& dir,
             const std::string& job_name) {
  static std::atomic<std::uint64_t> counter{0};
  const fs::path temp = dir.parent_path() /
                        fmt::format(".tmp-{}-{}-{}", dir.filename().string().substr(0, 16),
                                    ::getpid(), counter++);
  try {
    fs::create_directories(temp);
    for (const v1::AssetRef& ref : spec.assets()) {
      const fs::path to = temp / checked_relative_path(ref);
      std::error_code ec;
      fs::create_directories(to.parent_path(), ec);
      if (ec && is_disk_full_errno(ec.value())) throw fs::filesystem_error("cannot create", to.parent_path(), ec);
      if (ec || fs::exists(to)) {
        // One asset's path is a folder of another's ("a" and "a/b.obj").
        throw InputError(fmt::format("asset path '{}' conflicts with another asset's path",
                                     shown(ref.path())));
      }
      link_or_copy(store.path_of(ref.sha256()), to);
    }
    write_file(temp / job_name, spec.job_json());
    std::error_code ec;
    fs::rename(temp, dir, ec);
    // Someone else published the same scene first: theirs has the same contents.
    if (ec && !fs::is_directory(dir)) throw fs::filesystem_error("cannot publish", temp, dir, ec);
    if (ec) fs::remove_all(temp);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(temp, ignored);
    rethrow_as_disk_full(dir.parent_path());
  }
}

// The job's text under `job_name` in a published folder: the folder holds the text under the
// name the first submission of its scene gave it, and the same text may come under another name
// (the file name is not part of the scene hash), so it is written beside, atomically.
// A scene folder found laid out (by an earlier call, or a process before a restart) is a cache on
// disk: each of its files is hashed against its ref before the scene is loaded from it (docs/architecture.md,
// "every reply from another process or from a cache on disk is checked before it is trusted").
// Its files are links to the blobs, so a byte changed on disk changes both (issue #32: a job
// SUCCEEDED with 92% of its pixels wrong from such a file). True when every file is intact.
bool laid_out_intact(const v1::JobSpec& spec, const fs::path& dir) {
  for (const v1::AssetRef& ref : spec.assets()) {
    const fs::path file = dir / checked_relative_path(ref);
    std::error_code ec;
    if (!fs::is_regular_file(fs::symlink_status(file, ec)) || fs::file_size(file, ec) != ref.size() || ec) return false;
    try {
      if (sha256_file_hex(file) != ref.sha256()) return false;
    } catch (const std::exception&) {
      return false;  // unreadable: laid out again
    }
  }
  return true;
}

// Takes a damaged scene folder out of its name at once (a rename: whoever looks next lays it out
// anew), then deletes it.
void discard_scene_folder(const fs::path& dir) {
  static std::atomic<std::uint64_t> counter{0};
  const fs::path aside = dir.parent_path() / fmt::format(".damaged-{}-{}-{}", dir.filename().string().substr(0, 16),
                                                         ::getpid(), counter++);
  std::error_code ec;
  fs::rename(dir, aside, ec);
  if (!ec) fs::remove_all(aside, ec);
}

void ensure_job_file(const fs::path& dir, const std::string& job_name, const std::string& job_json) {
  const fs::path file = dir / job_name;
  std::error_code ec;
  if (fs::is_regular_file(fs::symlink_status(file, ec))) return;
  try {
    // DiskFull naming the folder when there is no room
    write_file_atomically(file, [&](const fs::path& temp) { write_file(temp, job_json); });
  } catch (const fs::filesystem_error&) {
    throw InputError(fmt::format("cannot write the job file '{}' into the scene folder", job_name));
  }
}

}  // namespace

MissingAssetsError::MissingAssetsError(std::vector<v1::AssetRef> missing)
    : std::runtime_error(missing_message(missing)), missing_(std::move(missing)) {}

CorruptAssetsError::CorruptAssetsError(std::vector<v1::AssetRef> corrupt)
    : MissingAssetsError(corrupt, corrupt_message(corrupt)) {}

fs::path checked_asset_path(const std::string& p) {
  const auto fail = [&](const std::string& why) {
    throw InputError(fmt::format("asset path '{}': {}", shown(p), why));
  };
  if (p.empty()) fail("empty");
  if (p.find('\0') != std::string::npos) fail("contains a NUL character");
  // Laid out under <data dir>/scenes/<hash>/, it must fit the file system's limits there too.
  if (p.size() > kMaxAssetPathBytes) {
    fail(fmt::format("{} bytes long; at most {}", p.size(), kMaxAssetPathBytes));
  }
  const fs::path path(p);
  if (path.is_absolute() || path.has_root_path()) fail("must be relative to the job's folder");
  for (const fs::path& part : path) {
    if (part == "..") fail("must not contain '..'");
    if (part.native().size() > kMaxFileNameBytes) {
      fail(fmt::format("a name of {} bytes; a file name holds at most {}", part.native().size(), kMaxFileNameBytes));
    }
  }
  const fs::path normal = path.lexically_normal();
  if (normal.empty() || normal == "." || !normal.has_filename()) fail("names no file");
  return normal;
}

void validate_asset_refs(const v1::JobSpec& spec) {
  // Each is a file to check, link and perhaps fetch: far more than a scene's textures need.
  if (spec.assets_size() > kMaxJobAssets) {
    throw InputError(fmt::format("the job lists {} asset files; at most {}", spec.assets_size(), kMaxJobAssets));
  }
  std::set<fs::path> seen;
  for (const v1::AssetRef& ref : spec.assets()) {
    const fs::path path = checked_relative_path(ref);
    if (!is_sha256_hex(ref.sha256())) {
      throw InputError(fmt::format("asset '{}': sha256 '{}' is not 64 lowercase hex digits",
                                   shown(ref.path()), shown(ref.sha256())));
    }
    if (!seen.insert(path).second) {
      throw InputError(fmt::format("asset path '{}' is listed twice", shown(ref.path())));
    }
  }
}

void check_asset_sizes(const v1::JobSpec& spec, const AssetStore& store) {
  for (const v1::AssetRef& ref : spec.assets()) {
    if (!store.has(ref.sha256())) continue;
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(store.path_of(ref.sha256()), ec);
    if (ec) continue;  // gone since: missing_assets' concern
    if (size != ref.size()) {
      // A blob is verified when stored: one of another size was cut short or grown since, unless
      // it still hashes to its name (then the job's size is wrong).
      if (!store.intact(ref.sha256())) {
        store.remove(ref.sha256());
        throw CorruptAssetsError({ref});
      }
      throw InputError(fmt::format("asset '{}' (sha256 {}): the job says {} bytes, the file has {}",
                                   shown(ref.path()), ref.sha256(), ref.size(), size));
    }
  }
}

std::vector<v1::AssetRef> missing_assets(const v1::JobSpec& spec, const AssetStore& store) {
  std::vector<v1::AssetRef> missing;
  std::set<std::string> seen;
  for (const v1::AssetRef& ref : spec.assets()) {
    if (!store.has(ref.sha256()) && seen.insert(ref.sha256()).second) missing.push_back(ref);
  }
  return missing;
}

MaterializedScene materialize_scene(const v1::JobSpec& spec, const std::string& scene_hash,
                                    const AssetStore& store, const fs::path& cache_dir) {
  if (!is_sha256_hex(scene_hash)) throw InputError(fmt::format("bad scene hash '{}'", shown(scene_hash)));
  validate_asset_refs(spec);
  check_asset_sizes(spec, store);
  std::set<fs::path> asset_paths;
  for (const v1::AssetRef& ref : spec.assets()) asset_paths.insert(checked_relative_path(ref));
  const std::string job_name = job_file_name(spec, asset_paths);

  const fs::path scenes = fs::weakly_canonical(fs::absolute(cache_dir)) / "scenes";
  try {
    fs::create_directories(scenes);
  } catch (const std::exception&) {
    rethrow_as_disk_full(scenes);
  }
  MaterializedScene result{scenes / scene_hash, scenes / scene_hash / job_name, {}};
  // A published folder is complete (it only ever appears by rename), but its files may have been
  // damaged since: checked, and laid out again from the blobs (themselves checked) if one was.
  if (fs::is_directory(result.dir) && !laid_out_intact(spec, result.dir)) discard_scene_folder(result.dir);
  if (!fs::is_directory(result.dir)) {
    if (auto missing = missing_assets(spec, store); !missing.empty()) {
      throw MissingAssetsError(std::move(missing));
    }
    // The laid-out files are links to the blobs: a damaged blob would be the scene's file.
    refuse_corrupt_assets(spec, store);
    lay_out(spec, store, result.dir, job_name);
  }
  ensure_job_file(result.dir, job_name, spec.job_json());

  JobLoadOptions options;
  options.asset_root = result.dir;
  try {
    result.job = parse_job(spec.job_json(), result.job_file, options);
  } catch (const InputError& e) {
    throw InputError(without_scene_folder(e.what(), result.dir));
  }
  return result;
}

std::string without_scene_folder(std::string message, const fs::path& scene_dir) {
  replace_all(message, scene_dir.string() + "/", "");
  replace_all(message, scene_dir.string(), "the job's folder");
  return message;
}

}  // namespace farm
