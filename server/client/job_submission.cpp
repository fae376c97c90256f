#include "server/client/job_submission.h"

#include <fmt/format.h>

#include <algorithm>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "renderer/util/confined_file.h"
#include "renderer/util/input_error.h"
#include "renderer/util/json_reader.h"
#include "server/client/model_dependencies.h"
#include "server/common/sha256.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

bool any_override(const RenderOverrides& o) {
  return o.engine || o.width || o.height || o.spp || o.threads || o.tile_size || o.max_depth || o.seed ||
         !o.add_aovs.empty() || o.image || o.preview || o.video || o.frames;
}

// The job's document with model paths relative to the root and the overrides written in, as
// text: its keys in nlohmann's order (sorted), two spaces an indent.
std::string rewritten_job_text(nlohmann::json doc, const Job& job, const fs::path& root, const RenderOverrides& o) {
  auto& objects = doc["scene"]["objects"];
  for (std::size_t i = 0; i < objects.size(); ++i) {
    objects[i]["file"] = job.scene.objects[i].file.lexically_relative(root).generic_string();
  }
  if (job.scene.environment && !job.scene.environment->map.empty()) {
    doc["scene"]["environment"]["map"] = job.scene.environment->map.lexically_relative(root).generic_string();
  }
  // The render block is touched only for an override of it: `doc["render"]` on a job without one
  // would write "render": null, which the scheduler refuses.
  const auto render = [&]() -> nlohmann::json& { return doc["render"]; };
  if (o.engine) render()["engine"] = *o.engine;
  if (o.width) render()["width"] = *o.width;
  if (o.height) render()["height"] = *o.height;
  if (o.spp) render()["spp"] = *o.spp;
  if (o.threads) render()["threads"] = *o.threads;
  if (o.tile_size) render()["tile_size"] = *o.tile_size;
  if (o.max_depth) render()["max_depth"] = *o.max_depth;
  if (o.seed) render()["seed"] = *o.seed;
  if (!o.add_aovs.empty()) {
    // The job's AOVs as parsed (overrides applied), written back in the job file's names.
    nlohmann::json aovs = nlohmann::json::array();
    for (Aov aov : kAllAovs)
      if (job.render.aovs.has(aov)) aovs.push_back(std::string(to_string(aov)));
    doc["output"]["aovs"] = aovs;
  }
  if (o.frames) doc["frames"]["only"] = {o.frames->first, o.frames->second};
  if (o.image) doc["output"]["image"] = o.image->generic_string();
  if (o.preview) {
    if (o.preview->empty()) {
      if (doc.contains("output")) doc["output"].erase("preview");
    } else {
      doc["output"]["preview"] = o.preview->generic_string();
    }
  }
  if (o.video) {
    if (o.video->empty()) {
      if (doc.contains("output")) doc["output"].erase("video");
    } else {
      doc["output"]["video"] = o.video->generic_string();
    }
  }
  return doc.dump(2) + "\n";
}

struct Digest {
  std::string sha256;
  std::uint64_t size = 0;
};

Digest digest_of(const ConfinedFile& file, const std::string& path) {
  std::string why;
  const int fd = file.allowed() ? open_confined(file, &why) : -1;
  if (fd < 0) {
    throw InputError(fmt::format("{}: cannot read '{}': {}", file.named.string(), path,
                                 file.allowed() ? why : file.reason));
  }
  Sha256 hash;
  Digest digest;
  std::array<char, 1 << 16> buffer;
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      throw InputError(fmt::format("{}: cannot read: {}", file.named.string(), std::strerror(err)));
    }
    if (n == 0) break;
    hash.update(buffer.data(), static_cast<std::size_t>(n));
    digest.size += static_cast<std::uint64_t>(n);
  }
  ::close(fd);
  digest.sha256 = hash.finish_hex();
  return digest;
}

}  // namespace

JobSubmission make_job_submission(const fs::path& job_file, const JobLoadOptions& load,
                                  const RenderOverrides& overrides) {
  JobSubmission out;
  // Read once and parsed once: the same text is sent, or the same document rewritten.
  const std::string text = read_job_file(job_file);
  nlohmann::json document = parse_json_strict(text, job_file.string());
  out.job = parse_job_document(document, job_file, load);
  apply_overrides(out.job, overrides);
  const fs::path job_dir = fs::weakly_canonical(fs::absolute(job_file).parent_path());
  const fs::path& root = out.job.asset_root;  // what parse_job confined the models to

  // The text goes as written only when it names each model as the scheduler will find it: by the
  // path under the root it resolves to. An absolute path inside the root, or a link in it, is
  // written as that path (issue #32: `farm submit` refused both, which `farm render` accepts).
  const auto as_resolved = [&](const std::string& written, const fs::path& file) {
    return fs::path(written).lexically_normal() == file.lexically_relative(root);
  };
  const auto files_as_resolved = [&] {
    // Each name once (parse_job resolves one name to one file): a scene places one model file
    // under many objects.
    std::map<std::string, const fs::path*> resolved;
    for (const JobObject& o : out.job.scene.objects) resolved.emplace(o.file_as_written, &o.file);
    if (const std::optional<JobEnvironment>& e = out.job.scene.environment; e && !e->map.empty()) {
      resolved.emplace(e->map_as_written, &e->map);
    }
    return std::all_of(resolved.begin(), resolved.end(), [&](const auto& n) { return as_resolved(n.first, *n.second); });
  };
  const bool as_written = job_dir == root && !any_override(overrides) && files_as_resolved();
  out.spec.set_job_json(as_written ? text : rewritten_job_text(std::move(document), out.job, root, overrides));
  out.spec.set_file_name(job_file.filename().string());

  std::map<std::string, fs::path> by_path;  // spec path -> the file to read (resolved)
  const auto add = [&](const ConfinedFile& file) {
    // confine_file allowed it: it lies in the root, resolved (no symlink leads out) and as named.
    // It goes under the name the model uses, since a worker lays the files out by those names.
    by_path.emplace(file.named.lexically_relative(root).generic_string(), file.resolved);
  };
  // Objects that share a model (a field of 100 cows is one cow.dae) share one scan of it.
  ModelDependencyScanner scanner(root);
  // parse_job confined the files the job names to the root already: resolved and inside.
  for (const fs::path& named : job_named_files(out.job)) by_path.emplace(named.lexically_relative(root).generic_string(), named);
  std::set<fs::path> models;
  for (const JobObject& object : out.job.scene.objects) {
    if (!models.insert(object.file).second) continue;  // its files are in by_path already
    for (const ConfinedFile& dependency : scanner.dependencies(object.file)) add(dependency);
  }
  out.files_scanned = scanner.files_scanned();
  // by_path holds each file once, so each is hashed once. Read through the same gate again: a file
  // swapped for a FIFO or a link since it was scanned is refused, not waited on or followed.
  for (const auto& [path, file] : by_path) {
    const ConfinedFile checked = confine_file(root, file, file.string(), ReferenceForm::relative_or_absolute);
    const Digest digest = digest_of(checked, path);
    v1::AssetRef* ref = out.spec.add_assets();
    ref->set_path(path);
    ref->set_sha256(digest.sha256);
    ref->set_size(digest.size);  // the bytes hashed, so size and hash always describe one file
    ++out.files_hashed;
    out.files.emplace(ref->sha256(), checked.resolved);
  }
  return out;
}

}  // namespace farm
