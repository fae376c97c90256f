#include "server/client/job_submission.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "renderer/scene/input_error.h"
#include "renderer/util/path_confinement.h"
#include "server/client/model_dependencies.h"
#include "server/common/sha256.h"

namespace farm {
namespace {

namespace fs = std::filesystem;

bool any_override(const RenderOverrides& o) {
  return o.engine || o.width || o.height || o.spp || o.threads || o.tile_size || o.max_depth || o.seed ||
         !o.add_aovs.empty() || o.image || o.preview;
}

// The job text with model paths relative to the root and the overrides written in.
std::string rewritten_job_text(const std::string& text, const Job& job, const fs::path& root,
                               const RenderOverrides& o) {
  // parse_job accepted the text already; it is parsed again here, once, because only an
  // ordered document writes the keys back in the user's order.
  nlohmann::ordered_json doc = nlohmann::ordered_json::parse(text);
  auto& objects = doc["scene"]["objects"];
  for (std::size_t i = 0; i < objects.size(); ++i) {
    objects[i]["file"] = job.scene.objects[i].file.lexically_relative(root).generic_string();
  }
  auto& render = doc["render"];
  if (o.engine) render["engine"] = *o.engine;
  if (o.width) render["width"] = *o.width;
  if (o.height) render["height"] = *o.height;
  if (o.spp) render["spp"] = *o.spp;
  if (o.threads) render["threads"] = *o.threads;
  if (o.tile_size) render["tile_size"] = *o.tile_size;
  if (o.max_depth) render["max_depth"] = *o.max_depth;
  if (o.seed) render["seed"] = *o.seed;
  if (!o.add_aovs.empty()) {
    // The job's AOVs as parsed (overrides applied), written back in the job file's names.
    nlohmann::ordered_json aovs = nlohmann::ordered_json::array();
    for (Aov aov : kAllAovs)
      if (job.render.aovs.has(aov)) aovs.push_back(std::string(to_string(aov)));
    doc["output"]["aovs"] = aovs;
  }
  if (o.image) doc["output"]["image"] = o.image->generic_string();
  if (o.preview) {
    if (o.preview->empty()) {
      doc["output"].erase("preview");
    } else {
      doc["output"]["preview"] = o.preview->generic_string();
    }
  }
  return doc.dump(2) + "\n";
}

}  // namespace

JobSubmission make_job_submission(const fs::path& job_file, const JobLoadOptions& load,
                                  const RenderOverrides& overrides) {
  JobSubmission out;
  // Read once: the same text is parsed here and sent.
  const std::string text = read_job_file(job_file);
  out.job = parse_job(text, job_file, load);
  apply_overrides(out.job, overrides);
  const fs::path job_dir = fs::weakly_canonical(fs::absolute(job_file).parent_path());
  const fs::path root = load.asset_root.empty() ? job_dir : fs::weakly_canonical(fs::absolute(load.asset_root));

  const bool as_written = job_dir == root && !any_override(overrides);
  out.spec.set_job_json(as_written ? text : rewritten_job_text(text, out.job, root, overrides));
  out.spec.set_file_name(job_file.filename().string());

  std::map<std::string, fs::path> by_path;  // spec path -> file
  const auto add = [&](const fs::path& file, const fs::path& model) {
    // Two conditions, both needed: the file must really lie in the root (resolved, so no symlink
    // leads out), and it must be named under the root as the model names it (lexically, since a
    // worker lays the files out by the names the models use, symlinks or not).
    const fs::path relative = file.lexically_relative(root);
    if (!resolve_within(root, file) || relative.empty() || *relative.begin() == "..") {
      throw InputError(fmt::format("{}: references {}, which lies outside the asset root {} (give "
                                   "--asset-root a folder that holds both)",
                                   model.string(), file.string(), root.string()));
    }
    by_path.emplace(relative.generic_string(), file);
  };
  // Objects that share a model (a field of 100 cows is one cow.dae) share one scan of it.
  ModelDependencyScanner scanner;
  for (const JobObject& object : out.job.scene.objects) {
    add(object.file, job_file);
    for (const fs::path& dependency : scanner.dependencies(object.file)) add(dependency, object.file);
  }
  out.files_scanned = scanner.files_scanned();
  // by_path holds each file once, so each is hashed once.
  for (const auto& [path, file] : by_path) {
    v1::AssetRef* ref = out.spec.add_assets();
    ref->set_path(path);
    ref->set_sha256(sha256_file_hex(file));
    ++out.files_hashed;
    ref->set_size(fs::file_size(file));
    out.files.emplace(ref->sha256(), file);
  }
  return out;
}

}  // namespace farm
