#include "server/scheduler/jobs/submission_plan.h"

#include <fmt/format.h>

#include <cstdint>
#include <map>
#include <set>

#include "renderer/util/input_error.h"
#include "renderer/util/path_confinement.h"
#include "renderer/util/utf8_text.h"
#include "server/common/model_references.h"
#include "server/common/read_whole_file.h"
#include "server/common/scene_materializer.h"

namespace farm {

namespace {

namespace fs = std::filesystem;

// The job's folder as a plan names it: a name only, never looked up on this machine. Messages
// call it what materialize_scene's do (without_scene_folder).
const fs::path kJobFolder = "/.farm-plan/job";
constexpr std::size_t kMaxShown = 200;

std::string shown(const std::string& s) {
  return s.size() <= kMaxShown ? s : utf8_prefix(s, kMaxShown) + "...";
}

// A name under the job's folder as an asset path ("assets/box.obj").
std::string asset_path_of(const fs::path& named) { return named.lexically_relative(kJobFolder).generic_string(); }

// The job's files as the spec describes them, resolved by name in the job's folder; their bytes
// from the store, when it holds them. Files referenced that the spec does not describe, and that
// the client did not find, are noted as needed.
class HeldFiles final : public ReferenceSource {
 public:
  HeldFiles(const v1::JobSpec& spec, const std::set<std::string>& absent, const AssetStore& store)
      : absent_(absent), store_(store) {
    for (const v1::AssetRef& ref : spec.assets()) assets_.emplace(checked_asset_path(ref.path()).generic_string(), &ref);
  }

  std::optional<fs::path> locate(const fs::path& model, const fs::path& referrer,
                                 const ModelReference& reference) override {
    // In confine_file's words, after the names of the model and the library that makes it.
    const auto refuse = [&](const std::string& why) {
      const std::string message = fmt::format("{}: '{}' {}", asset_path_of(referrer), shown(reference.local), why);
      throw InputError(referrer == model ? message : asset_path_of(model) + ": " + message);
    };
    if (reference.local.find('\0') != std::string::npos) refuse("contains a NUL character");
    if (fs::path(reference.local).has_root_path()) {
      refuse("is an absolute path (a model names its files relative to its own folder)");
    }
    const fs::path named = (referrer.parent_path() / reference.local).lexically_normal();
    if (!lies_within(kJobFolder, named)) refuse("lies outside the asset root (the job's folder)");
    if (!named.has_filename()) refuse("names a folder, not a file");
    const std::string path = asset_path_of(named);
    if (!is_utf8(path)) refuse("is not UTF-8, and a plan names files in UTF-8");
    try {
      checked_asset_path(path);
    } catch (const InputError& e) {
      refuse(fmt::format("cannot be a job's file: {}", e.what()));
    }
    if (assets_.count(path)) return named;
    if (absent_.count(path) || needed_.count(path)) return std::nullopt;
    if (assets_.size() + absent_.size() + needed_.size() >= static_cast<std::size_t>(kMaxJobAssets)) {
      throw InputError(fmt::format("the job reads more than {} files; a scheduler takes at most {}", kMaxJobAssets,
                                   kMaxJobAssets));
    }
    v1::NeededFile& needed = needed_[path];
    needed.set_path(path);
    needed.set_named_by(asset_path_of(referrer));
    needed.set_reference(is_utf8(reference.written) ? shown(reference.written) : shown(reference.local));
    return std::nullopt;
  }

  std::optional<std::string> read(const fs::path& file, const char* what) override {
    const auto found = assets_.find(asset_path_of(file));
    if (found == assets_.end() || !store_.has(found->second->sha256())) return std::nullopt;
    // check_asset_sizes held the blob to the size its ref declares, which check_spec_limits held
    // to the asset limits; the scanner reads each file once.
    return read_whole_file(store_.path_of(found->second->sha256()), what);
  }

  void add_needed(const std::string& path, const std::string& named_by, const std::string& reference) {
    v1::NeededFile& needed = needed_[path];
    needed.set_path(path);
    needed.set_named_by(named_by);
    needed.set_reference(shown(reference));
  }
  bool described(const std::string& path) const { return assets_.count(path) > 0; }
  const std::map<std::string, v1::NeededFile>& needed() const { return needed_; }

 private:
  const std::set<std::string>& absent_;
  const AssetStore& store_;
  std::map<std::string, const v1::AssetRef*> assets_;  // by path, lexically normal
  std::map<std::string, v1::NeededFile> needed_;       // by path: sorted, each once
};

}  // namespace

v1::PlanSubmissionResponse plan_submission(const v1::PlanSubmissionRequest& request, const AssetStore& store,
                                           const SubmitLimits& limits) {
  const v1::JobSpec& spec = request.job();
  // As SubmitJob checks a spec, before anything is parsed or read.
  check_spec_limits(spec, limits);
  validate_asset_refs(spec);
  if (spec.assets_size() + request.absent_size() > kMaxJobAssets) {
    throw InputError(fmt::format("PlanSubmission: {} assets and {} absent files; a job reads at most {}",
                                 spec.assets_size(), request.absent_size(), kMaxJobAssets));
  }
  std::set<std::string> absent;
  for (const std::string& path : request.absent()) {
    const std::string normal = checked_asset_path(path).generic_string();
    absent.insert(normal);
  }
  check_asset_sizes(spec, store);

  // The job as it will be laid out: parse_job's checks and messages, its models by name.
  const fs::path job_file = kJobFolder / (spec.file_name().empty() ? fs::path("job.json")
                                                                   : fs::path(spec.file_name()).filename());
  JobLoadOptions options;
  options.asset_root = kJobFolder;
  options.models_by_name = true;
  Job job;
  try {
    job = parse_job(spec.job_json(), job_file, options);
  } catch (const InputError& e) {
    throw InputError(without_scene_folder(e.what(), kJobFolder));
  }
  check_job_limits(job, spec, limits);

  HeldFiles files(spec, absent, store);
  for (const std::string& path : absent) {
    if (files.described(path)) {
      throw InputError(fmt::format("PlanSubmission: '{}' is both an asset and absent", shown(path)));
    }
  }
  ModelReferenceScanner scanner(files);
  // The files the job names itself: each must be sent, and a model is scanned for the files it
  // names in turn (an image names none).
  const auto plan_named = [&](const fs::path& file, const std::string& place, const std::string& as_written,
                              bool model) {
    const std::string path = asset_path_of(file);
    if (absent.count(path)) {
      throw InputError(fmt::format("{}: {}: no such file '{}'", job_file.filename().string(), place, shown(as_written)));
    }
    if (!files.described(path)) {
      files.add_needed(path, job_file.filename().string(), as_written);
      return;
    }
    if (model) scanner.references(file);
  };
  for (std::size_t i = 0; i < job.scene.objects.size(); ++i) {
    const JobObject& object = job.scene.objects[i];
    plan_named(object.file, fmt::format("scene.objects[{}].file", i), object.file_as_written, true);
  }
  if (const auto& environment = job.scene.environment; environment && !environment->map.empty()) {
    plan_named(environment->map, "scene.environment.map", environment->map_as_written, false);
  }

  v1::PlanSubmissionResponse response;
  for (const v1::AssetRef& ref : missing_assets(spec, store)) response.add_missing_sha256(ref.sha256());
  for (const auto& [path, needed] : files.needed()) *response.add_needed() = needed;
  response.set_complete(response.missing_sha256().empty() && response.needed().empty());
  return response;
}

}  // namespace farm
